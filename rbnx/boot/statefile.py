"""The boot state file and the per-deployment run dir: what `rbnx shutdown -f deploy.yaml` finds.

A deployment is a deploy file booted against one atlas address: the same file may run twice on one host
with different `system.atlas.listen` (and ROS domains), and the two must never see each other's files.
So the state file is keyed by deploy path + configured atlas listen address (plus the boot's PID when
the port is 0, i.e. picked by the OS), and the run dir handed to packages (RBNX_RUN_DIR: pidfiles of
native starts) by deploy name + the atlas's actual address.

State files live under $RBNX_STATE_DIR, else $XDG_RUNTIME_DIR/rbnx, else /tmp/rbnx-<uid>; a copy lives
in the log directory for post-mortems. PIDs are stored with their /proc start time so a reused PID is
never signalled.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import re
import tempfile
from pathlib import Path
from typing import Any


def state_dir() -> Path:
    if os.environ.get("RBNX_STATE_DIR"):
        return Path(os.environ["RBNX_STATE_DIR"])
    if os.environ.get("XDG_RUNTIME_DIR"):
        return Path(os.environ["XDG_RUNTIME_DIR"]) / "rbnx"
    return Path(tempfile.gettempdir()) / f"rbnx-{os.getuid()}"


def _digest(text: str, n: int) -> str:
    return hashlib.sha1(text.encode()).hexdigest()[:n]


def _port_is_zero(listen: str) -> bool:
    return listen.rpartition(":")[2] == "0"


def _state_stem(deploy_path: Path, listen: str) -> str:
    path_key = _digest(str(Path(deploy_path).resolve()), 12)
    return f"boot-{Path(deploy_path).stem}-{path_key}" + (f"-{_digest(listen, 8)}" if listen else "")


def state_path(deploy_path: Path, listen: str = "", pid: int | None = None) -> Path:
    """The state file of the deployment (deploy file, configured atlas listen address).

    With an OS-picked port (``:0``) several boots of one file can run at once, so each adds its PID.
    """
    stem = _state_stem(deploy_path, listen)
    if pid is not None and _port_is_zero(listen):
        stem += f"-p{pid}"
    return state_dir() / f"{stem}.json"


def find_states(deploy_path: Path, listen: str = "") -> list[Path]:
    """Existing state files of this deployment: the exact one, or the per-PID ones of a ``:0`` listen."""
    exact = state_path(deploy_path, listen)
    found = [exact] if exact.is_file() else []
    if _port_is_zero(listen):
        found += sorted(state_dir().glob(f"{exact.stem}-p*.json"))
    return found


def _safe(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", text).strip("_.-") or "x"


def deployment_key(name: str, atlas_addr: str) -> str:
    """A file-name-safe id of one running deployment: deploy name + the atlas address it serves."""
    return f"{_safe(name)}-{_safe(atlas_addr)}"


def run_dir(name: str, atlas_addr: str, env: dict[str, str] | None = None) -> Path:
    """Where a deployment's packages keep runtime files (RBNX_RUN_DIR): one folder per deployment.

    Base: $RBNX_RUN_DIR, else $XDG_RUNTIME_DIR/robonix, else <tmp>/robonix-<uid>.
    """
    env = os.environ if env is None else env
    if env.get("RBNX_RUN_DIR"):
        base = Path(env["RBNX_RUN_DIR"])
    elif env.get("XDG_RUNTIME_DIR"):
        base = Path(env["XDG_RUNTIME_DIR"]) / "robonix"
    else:
        base = Path(tempfile.gettempdir()) / f"robonix-{os.getuid()}"
    return base / deployment_key(name, atlas_addr)


def write_state(path: Path, data: dict[str, Any], copy_to: Path | None = None) -> None:
    """Atomic write (tmp + rename) so a reader never sees half a file; mode 0600 (it holds the deployment
    token), the copy too."""
    path.parent.mkdir(parents=True, exist_ok=True)
    text = json.dumps(data, indent=2)
    tmp = path.with_suffix(f".tmp{os.getpid()}")
    _write_private(tmp, text)
    os.replace(tmp, path)
    if copy_to is not None:
        with contextlib.suppress(OSError):
            _write_private(copy_to, text)


def _write_private(path: Path, text: str) -> None:
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    os.fchmod(fd, 0o600)  # an existing file keeps its mode through O_CREAT
    with os.fdopen(fd, "w") as fh:
        fh.write(text)


def read_state(path: Path) -> dict[str, Any] | None:
    try:
        return json.loads(path.read_text())
    except (OSError, json.JSONDecodeError):
        return None


def remove_state(path: Path) -> None:
    with contextlib.suppress(FileNotFoundError):
        path.unlink()


def restarts_for_atlas(atlas_addr: str) -> dict[str, int]:
    """Process restarts per entry name (and ``atlas``) of the running boot that serves ``atlas_addr``,
    read from its state file; empty when no boot of this user serves that address."""
    out: dict[str, int] = {}
    try:
        files = sorted(state_dir().glob("boot-*.json"))
    except OSError:
        return out
    for f in files:
        st = read_state(f)
        if not st or st.get("atlas") != atlas_addr:
            continue
        for c in st.get("children") or []:
            if c.get("restarts"):
                out[str(c.get("name"))] = int(c["restarts"])
        if (st.get("atlas_proc") or {}).get("restarts"):
            out["atlas"] = int(st["atlas_proc"]["restarts"])
    return out


def gateways(atlas_addr: str | None = None) -> list[dict[str, str]]:
    """The MCP gateways of running boots (from their state files), optionally only those of one atlas."""
    out = []
    for f in sorted(state_dir().glob("boot-*.json")):
        st = read_state(f)
        if st and st.get("gateway") and (atlas_addr is None or st.get("atlas") == atlas_addr):
            out.append({"url": str(st["gateway"]), "deploy": str(st.get("deploy", "")), "atlas": str(st.get("atlas"))})
    return out
