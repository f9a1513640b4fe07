"""Loopback-only config in effect; malformed CYCLONEDDS_URI fails fast and clearly."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from robonix_api.dds import DdsNode, effective_config
from robonix_api.dds.config import DEFAULT_CONFIG, probe_runtime

CHILD = "from robonix_api.dds import DdsNode\nDdsNode().close()\nprint('OK')\n"


def run_child(uri: str | None, timeout: float = 60.0) -> tuple[subprocess.CompletedProcess, float]:
    env = dict(os.environ)
    if uri is None:
        env.pop("CYCLONEDDS_URI", None)
    else:
        env["CYCLONEDDS_URI"] = uri
    t = time.monotonic()
    res = subprocess.run([sys.executable, "-c", CHILD], env=env, capture_output=True, text=True, timeout=timeout)
    return res, time.monotonic() - t


def test_running_cyclone_selected_only_lo() -> None:
    """Cyclone's own trace of the config in use: only lo selected, no multicast on it."""
    rt = probe_runtime()
    assert rt["selected_interfaces"] == ["lo"], rt
    assert rt["multicast_interfaces"] == [], rt
    assert rt["allow_multicast"] == "false", rt


def test_node_reports_config(node: DdsNode) -> None:
    assert node.config["loopback_only"]
    assert node.domain_id == int(os.environ["ROS_DOMAIN_ID"])


def test_default_config_when_uri_unset(tmp_path: Path) -> None:
    res, _ = run_child(None)
    assert res.returncode == 0, res.stderr
    assert "OK" in res.stdout, res.stderr
    assert DEFAULT_CONFIG.is_file()


@pytest.mark.parametrize(("content", "expect"), [
    (None, "does not exist"),
    ("<CycloneDDS><Domain><General>", "not well-formed XML"),
    ("<Cyclone/>", "root element"),
    ("<CycloneDDS><Domain><General><NoSuchSetting>1</NoSuchSetting></General></Domain></CycloneDDS>",
     "rejected config"),
])
def test_bad_uri_fails_fast_with_clear_error(tmp_path: Path, content: str | None, expect: str) -> None:
    path = tmp_path / "cdds.xml"
    if content is not None:
        path.write_text(content)
    res, took = run_child(path.as_uri())
    assert res.returncode != 0
    assert "DdsConfigError" in res.stderr, res.stderr[-1500:]
    assert expect in res.stderr, res.stderr[-1500:]
    assert took < 30.0  # a clear failure, never a hang (generous for a loaded 2-core box)


LOOPBACK_FRAGMENTS = ('<General><Interfaces><NetworkInterface name="lo"/></Interfaces>'
                      "<AllowMulticast>false</AllowMulticast></General>"
                      '<Discovery><ParticipantIndex>auto</ParticipantIndex><Peers><Peer address="127.0.0.1"/></Peers>'
                      "</Discovery>")


def test_inline_fragments_without_a_root_as_cyclone_takes_them(monkeypatch: pytest.MonkeyPatch) -> None:
    """``<General>…</General><Discovery>…</Discovery>`` (no root element) is valid for Cyclone: ours too."""
    monkeypatch.setenv("CYCLONEDDS_URI", LOOPBACK_FRAGMENTS)
    cfg = effective_config()
    assert cfg["interfaces"] == ["lo"], cfg
    assert cfg["multicast_disabled"], cfg
    assert cfg["loopback_only"], cfg
    assert probe_runtime()["selected_interfaces"] == ["lo"]  # Cyclone itself read the fragments
    res, _ = run_child(LOOPBACK_FRAGMENTS)
    assert res.returncode == 0, res.stderr[-1500:]
    assert "OK" in res.stdout, res.stderr[-1500:]
    res, _ = run_child("<General><Interfaces></General>")  # fragments, but not well-formed
    assert res.returncode != 0, res.stderr[-1500:]
    assert "not well-formed XML" in res.stderr, res.stderr[-1500:]
