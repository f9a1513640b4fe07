"""Which Cyclone DDS configuration a node uses, validated before any participant exists.

Cyclone parses ``CYCLONEDDS_URI`` itself, but a typo there surfaces as an opaque failure (or a default,
multicast-enabled config silently taking over). We check it first and raise ``DdsConfigError`` naming
the problem. Unset ``CYCLONEDDS_URI`` means the project's loopback-only config.
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any
from urllib.parse import unquote, urlparse

from robonix_nav_data import resources

DEFAULT_CONFIG = resources.config_file("cyclonedds_loopback.xml")
MAX_DOMAIN_ID = 232  # highest id Cyclone's default port mapping supports


class DdsConfigError(RuntimeError):
    """The DDS configuration (CYCLONEDDS_URI, ROS_DOMAIN_ID) is unusable; the message says why."""


def resolve_domain_id(domain_id: int | None = None) -> int:
    """Explicit id, else ``ROS_DOMAIN_ID``, else 0 (ROS 2's rule)."""
    if domain_id is None:
        raw = os.environ.get("ROS_DOMAIN_ID", "").strip()
        if not raw:
            return 0
        try:
            domain_id = int(raw)
        except ValueError:
            raise DdsConfigError(f"ROS_DOMAIN_ID={raw!r} is not an integer") from None
    if not 0 <= int(domain_id) <= MAX_DOMAIN_ID:
        raise DdsConfigError(f"domain id {domain_id} out of range 0..{MAX_DOMAIN_ID}")
    return int(domain_id)


def _split(uri: str) -> list[str]:
    """CYCLONEDDS_URI: comma-separated files/URIs/inline XML; a comma inside inline XML does not split."""
    parts: list[str] = []
    for piece in uri.split(","):
        if parts and parts[-1].lstrip().startswith("<") and not piece.lstrip().startswith(("<", "file:", "/")):
            parts[-1] += "," + piece
        else:
            parts.append(piece)
    return [p.strip() for p in parts if p.strip()]


def _load(part: str) -> tuple[str, ET.Element]:
    """One config element -> (label, parsed root); raises DdsConfigError."""
    if part.startswith("<"):
        label, text = "inline XML", part
    else:
        path = Path(unquote(urlparse(part).path)) if part.startswith("file:") else Path(part)
        label = str(path)
        if not path.is_file():
            raise DdsConfigError(f"Cyclone DDS config {label} (from CYCLONEDDS_URI) does not exist or is not a file")
        try:
            text = path.read_text()
        except OSError as exc:
            raise DdsConfigError(f"Cyclone DDS config {label} cannot be read: {exc}") from exc
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        root = _fragments(text) if label == "inline XML" else None
        if root is None:
            raise DdsConfigError(f"Cyclone DDS config {label} is not well-formed XML: {exc}") from exc
    return label, root


def _fragments(text: str) -> ET.Element | None:
    """Inline XML as Cyclone also takes it: a run of elements without one root.

    ``<General>…</General><Discovery>…</Discovery>`` is what ROS 2 users paste from Cyclone's docs; Cyclone
    reads it as the inside of ``<CycloneDDS><Domain>``. Returns None when it is not well-formed that way either.
    """
    body = text.strip()
    if body.startswith("<?xml"):
        body = body.split("?>", 1)[-1]
    try:
        return ET.fromstring(f"<Domain>{body}</Domain>")
    except ET.ParseError:
        return None


def resolve_config() -> tuple[str, str, list[tuple[str, ET.Element]]]:
    """(uri to hand to Cyclone, source 'env'|'default', parsed elements) — validated."""
    uri = os.environ.get("CYCLONEDDS_URI")
    source = "env"
    if uri is None or not uri.strip():
        if not DEFAULT_CONFIG.is_file():
            raise DdsConfigError(f"CYCLONEDDS_URI unset and the default config {DEFAULT_CONFIG} is missing")
        uri, source = DEFAULT_CONFIG.as_uri(), "default"
    parsed = [_load(p) for p in _split(uri)]
    if not parsed:
        raise DdsConfigError(f"CYCLONEDDS_URI={uri!r} names no configuration")
    for label, root in parsed:
        if label != "inline XML" and _local(root.tag) not in ("CycloneDDS", "Domain"):
            raise DdsConfigError(f"Cyclone DDS config {label}: root element must be <CycloneDDS>, "
                                 f"got <{_local(root.tag)}>")
    return uri, source, parsed


def _local(tag: str) -> str:
    return tag.rsplit("}", 1)[-1]


def _find_all(root: ET.Element, name: str) -> list[ET.Element]:
    return [e for e in root.iter() if _local(e.tag) == name]


def summarize(parsed: list[tuple[str, ET.Element]]) -> dict[str, Any]:
    """Interfaces, multicast and peers as the (last-wins) config fragments set them."""
    interfaces: list[str] = []
    multicast: str | None = None
    peers: list[str] = []
    max_msg: str | None = None
    frag: str | None = None
    for _label, root in parsed:
        found = [e.get("name") or e.get("address") or "" for e in _find_all(root, "NetworkInterface")]
        found += [(e.text or "").strip() for e in _find_all(root, "NetworkInterfaceAddress")]
        if found:
            interfaces = [f for f in found if f]
        for e in _find_all(root, "AllowMulticast"):
            multicast = (e.text or "").strip().lower()
        peers += [p.get("address", "") for p in _find_all(root, "Peer")]
        for e in _find_all(root, "MaxMessageSize"):
            max_msg = (e.text or "").strip()
        for e in _find_all(root, "FragmentSize"):
            frag = (e.text or "").strip()
    return {
        "interfaces": interfaces,
        "allow_multicast": multicast if multicast is not None else "default",
        "multicast_disabled": multicast == "false",
        "peers": peers,
        "max_message_size": max_msg,
        "fragment_size": frag,
        "loopback_only": bool(interfaces) and all(i in ("lo", "127.0.0.1", "::1") for i in interfaces)
        and all(p.split(":")[0] in ("127.0.0.1", "localhost") for p in peers),
    }


def effective_config() -> dict[str, Any]:
    """What a DdsNode created now would use: uri, source, interfaces, multicast, peers."""
    uri, source, parsed = resolve_config()
    out = {"uri": uri, "source": source, "files": [label for label, _ in parsed]}
    out.update(summarize(parsed))
    return out


_PROBE = """
import sys
from cyclonedds.domain import DomainParticipant
DomainParticipant(int(sys.argv[1]))
"""


def probe_runtime(domain_id: int | None = None, timeout_s: float = 30.0) -> dict[str, Any]:
    """Ask Cyclone itself which interfaces it selected: start a throwaway participant in a child process
    with the config in use plus a ``config`` trace, and read the trace. Not free (a process start), so
    meant for tests and the benchmark, not for every node."""
    import re
    import subprocess
    import sys
    import tempfile

    uri, _source, _parsed = resolve_config()
    did = resolve_domain_id(domain_id)
    with tempfile.TemporaryDirectory() as tmp:
        log = Path(tmp) / "cdds.log"
        trace = f"<Tracing><Category>config</Category><OutputFile>{log}</OutputFile></Tracing>"
        env = dict(os.environ, CYCLONEDDS_URI=f"{uri},{trace}")
        subprocess.run([sys.executable, "-c", _PROBE, str(did)], env=env, timeout=timeout_s, check=True,
                       capture_output=True)
        text = log.read_text(errors="replace")
    sel = re.search(r"selected interfaces: (.*)", text)
    mc = re.search(r"General/AllowMulticast/#text: (\S+)", text)
    names = re.findall(r"(\S+) \(index \d+ priority \S+ mc \{([^}]*)\}\)", sel.group(1)) if sel else []
    return {
        "selected_interfaces": [n for n, _ in names],
        "multicast_interfaces": [n for n, m in names if m.strip()],
        "allow_multicast": mc.group(1) if mc else None,
        "trace_line": sel.group(0) if sel else None,
    }
