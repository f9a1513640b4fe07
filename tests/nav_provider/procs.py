"""Provider child processes for the navigation tests and the latency bench: start, find through the
atlas, drive the lifecycle Driver, stop by PID (SIGTERM, SIGKILL after a grace period)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import grpc

from robonix_api.atlas_client import AtlasClient
from robonix_api.proto_gen import lifecycle_pb2, robonix_contracts_pb2_grpc

DRIVER = "robonix/lifecycle/driver"
REPO = Path(__file__).resolve().parents[2]
MAP_PROVIDER = [sys.executable, str(Path(__file__).resolve().parent / "map_provider.py")]
NAV = [sys.executable, "-m", "nav2_wrapper.atlas_bridge"]
HAL = [sys.executable, "-m", "hal_panda_mobile"]
INIT, ACTIVATE, DEACTIVATE, SHUTDOWN = 0, 1, 2, 3


def wait_until(pred: Callable[[], Any], timeout_s: float, what: str, interval: float = 0.05) -> Any:
    deadline = time.monotonic() + timeout_s
    while True:
        value = pred()
        if value:
            return value
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout_s} s waiting for {what}")
        time.sleep(interval)


def alive(pid: int) -> bool:
    """Running and not a zombie (from /proc)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat[stat.rfind(")") + 2] not in "ZX"


class Proc:
    """One provider child registered under ``name``; ``driver()`` speaks its lifecycle Driver."""

    def __init__(self, cmd: list[str], atlas: str, name: str, log_path: Path, env: dict[str, str] | None = None) -> None:
        self.atlas, self.name, self.log_path = atlas, name, log_path
        full_env = dict(os.environ, ROBONIX_ATLAS=atlas, RBNX_INSTANCE_NAME=name, PYTHONUNBUFFERED="1",
                        ROBONIX_HEARTBEAT_PERIOD_S="2", **(env or {}))
        full_env.pop("RBNX_DEPLOY_MANAGED", None)
        self._log = open(log_path, "w")  # noqa: SIM115 (closed in stop())
        self.proc = subprocess.Popen(cmd, env=full_env, cwd=REPO, stdout=self._log, stderr=subprocess.STDOUT,
                                     stdin=subprocess.DEVNULL)
        self.client = AtlasClient(atlas)
        self._channels: list[grpc.Channel] = []
        endpoint = wait_until(lambda: self.endpoint(DRIVER), 120, f"{name} to declare its driver", 0.2)
        self._driver = robonix_contracts_pb2_grpc.RobonixLifecycleDriverStub(self._channel(endpoint))

    def _channel(self, endpoint: str) -> grpc.Channel:
        ch = grpc.insecure_channel(endpoint)
        self._channels.append(ch)
        return ch

    def endpoint(self, contract_id: str, transport: str = "grpc") -> str:
        if self.proc.poll() is not None:
            raise AssertionError(f"{self.name} exited with {self.proc.returncode}:\n{self.log()[-4000:]}")
        if not self.client.find_capability(contract_id=contract_id, transport=transport, provider_id=self.name):
            return ""
        with self.client.connect_capability(consumer_id="nav_test", provider_id=self.name, contract_id=contract_id,
                                            transport=transport) as ch:
            return ch.endpoint

    def stub(self, contract_id: str, stub_cls: type) -> Any:
        """A gRPC stub for a contract found through the atlas (find → ConnectCapability → endpoint)."""
        return stub_cls(self._channel(self.endpoint(contract_id)))

    def log(self) -> str:
        return self.log_path.read_text(errors="replace")

    def driver(self, command: int, config: dict[str, Any] | None = None) -> tuple[bool, str, str]:
        req = lifecycle_pb2.Driver_Request(command=command, config_json=json.dumps(config or {}))
        resp = self._driver.Driver(req, timeout=180)
        return resp.ok, resp.state, resp.error

    def stop(self) -> int:
        """SIGTERM by PID, SIGKILL after 30 s; asserts the process is gone."""
        pid = self.proc.pid
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(30)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(10)
        for ch in self._channels:
            ch.close()
        self.client.close()
        self._log.close()
        assert not alive(pid), f"{self.name} pid {pid} still alive"
        return self.proc.returncode
