"""`rbnx describe --check` (the container healthcheck) against a real atlas."""

from __future__ import annotations

import subprocess
import sys

from atlas.server import AtlasServer
from robonix_api.atlas_client import AtlasClient
from robonix_api.types import LifecycleState


def check(addr: str, pid: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "rbnx.cli", "--atlas", addr, "describe", "--provider", pid,
                           "--check"], capture_output=True, text=True, timeout=60)


def test_describe_check_exit_codes() -> None:
    with AtlasServer(listen="127.0.0.1:0") as server:
        client = AtlasClient(server.address)
        try:
            client.register_service("nav2", "robonix/service/navigation")
            client.set_state("nav2", LifecycleState.ACTIVE)
            ok = check(server.address, "nav2")
            assert ok.returncode == 0
            assert ok.stdout.strip() == "nav2: active"
            client.set_state("nav2", LifecycleState.TERMINATED, "heartbeat lapsed > 90000ms")
            dead = check(server.address, "nav2")
            assert dead.returncode == 1
            assert "terminated" in dead.stdout
            assert check(server.address, "ghost").returncode == 1
        finally:
            client.close()
