"""`rbnx boot --dashboard`: the dashboard finds the atlas of the boot it belongs to (from the boot's state
file, also when the OS picked the atlas port), shows every provider's lifecycle state, and goes away with
the boot on Ctrl-C. Uses examples/minimal (two small providers), so it is cheap."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
from pathlib import Path

import pytest
from support.boot import rbnx_cmd
from support.browser import free_port
from support.procs import wait_until

pytestmark = [pytest.mark.integration, pytest.mark.slow, pytest.mark.timeout(300)]

MINIMAL = Path(__file__).resolve().parents[4] / "examples" / "minimal" / "deploy.yaml"


def test_boot_dashboard_shows_the_boots_providers(tmp_path: Path) -> None:
    from websockets.sync.client import connect

    port = free_port()
    env = dict(os.environ, RBNX_STATE_DIR=str(tmp_path / "state"), RBNX_ATLAS_LISTEN="127.0.0.1:0",
               PYTHONUNBUFFERED="1")
    for name in ("ROBONIX_ATLAS", "RBNX_INSTANCE_NAME", "RBNX_DEPLOY_MANAGED"):
        env.pop(name, None)
    out = tmp_path / "boot.out"
    with open(out, "w") as fh:
        proc = subprocess.Popen(rbnx_cmd() + ["boot", "-f", str(MINIMAL), "--no-progress", "--log-dir",
                                              str(tmp_path / "logs"), "--dashboard", str(port)],
                                env=env, stdout=fh, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
    try:
        wait_until(lambda: "2/2 entries ready" in out.read_text() or proc.poll() is not None, 120, "the boot")
        assert proc.poll() is None, out.read_text()
        printed = re.search(rf"dashboard at (http://127\.0\.0\.1:{port}/\?token=(\S+))", out.read_text())
        assert printed, out.read_text()
        with connect(f"ws://127.0.0.1:{port}/ws", open_timeout=30,  # the key of the printed URL
                     additional_headers={"Authorization": f"Bearer {printed.group(2)}"}) as ws:
            def states() -> dict[str, str] | None:
                try:
                    snap = json.loads(ws.recv(timeout=5))
                except TimeoutError:  # nothing changed for a while: poll again
                    return None
                got = {p["id"]: p["state"] for p in snap["providers"]}
                return got if got.get("odom_primitive") == "active" and got.get("odom_consumer") == "active" else None

            got = wait_until(states, 60, "both providers shown active")
        assert set(got) >= {"odom_primitive", "odom_consumer"}
        proc.send_signal(signal.SIGINT)
        assert proc.wait(120) == 0, out.read_text()
        assert "Traceback" not in out.read_text(), out.read_text()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(30)
