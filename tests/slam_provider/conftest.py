"""Real processes for the SLAM provider tests: an in-process atlas, the HAL and the SLAM provider as children.

Every child is found through the atlas like any consumer would find it, driven over its lifecycle
Driver, and stopped by its own PID (SIGTERM, SIGKILL after a grace period); the fixtures assert none is
left behind. Deadlines are generous: the machine is shared and has two cores.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import grpc
import pytest

from robonix_api.atlas_client import AtlasClient
from robonix_api.proto_gen import lifecycle_pb2, robonix_contracts_pb2_grpc

DRIVER = "robonix/lifecycle/driver"
REPO = Path(__file__).resolve().parents[2]
SLAM = [sys.executable, "-m", "slam_service"]
HAL = [sys.executable, "-m", "hal_panda_mobile"]
INIT, ACTIVATE, DEACTIVATE, SHUTDOWN = 0, 1, 2, 3
# A small closed room with a few boxes: quick to map, distinctive enough to localize in.
SCENE: dict[str, Any] = {
    "name": "slam_test_room", "bounds": [0, 0, 6, 5],
    "walls": [{"start": a, "end": b, "thickness": 0.1, "height": 2.0}
              for a, b in (([0, 0], [6, 0]), ([6, 0], [6, 5]), ([6, 5], [0, 5]), ([0, 5], [0, 0]))],
    "boxes": [{"name": "crate", "center": [4.2, 1.2], "size": [0.6, 0.8], "height": 0.8},
              {"name": "shelf", "center": [1.0, 3.9], "size": [1.2, 0.4], "height": 1.5},
              {"name": "pillar", "center": [3.3, 3.4], "size": [0.3, 0.3], "height": 2.0}],
    "start": {"x": 1.5, "y": 1.5, "yaw": 0.0},
}
HAL_CONFIG: dict[str, Any] = {"scene": SCENE, "real_time_factor": 4.0, "odom_noise": "none",
                              "lidar_noise": {"noise_std": 0.0, "dropout_prob": 0.0}}


def wait_until(pred: Callable[[], Any], timeout_s: float, what: str, interval: float = 0.1) -> Any:
    deadline = time.monotonic() + timeout_s
    while True:
        value = pred()
        if value:
            return value
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout_s} s waiting for {what}")
        time.sleep(interval)


def alive(pid: int) -> bool:
    """Running and not a zombie (from /proc, no psutil)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat[stat.rfind(")") + 2] not in "ZX"


class Proc:
    """One provider child registered under ``name``; ``driver()`` speaks its lifecycle Driver."""

    def __init__(self, cmd: list[str], atlas: str, name: str, log_path: Path, env: dict[str, str] | None) -> None:
        self.atlas, self.name, self.log_path = atlas, name, log_path
        full = dict(os.environ, ROBONIX_ATLAS=atlas, RBNX_INSTANCE_NAME=name, PYTHONUNBUFFERED="1",
                    ROBONIX_HEARTBEAT_PERIOD_S="2", **(env or {}))
        full.pop("RBNX_DEPLOY_MANAGED", None)
        self._log = open(log_path, "w")  # noqa: SIM115 (closed in stop())
        self.proc = subprocess.Popen(cmd, env=full, cwd=REPO, stdout=self._log, stderr=subprocess.STDOUT,
                                     stdin=subprocess.DEVNULL)
        self.client = AtlasClient(atlas)
        self._channels: list[grpc.Channel] = []
        endpoint = wait_until(self._driver_endpoint, 90, f"{name} to declare its driver", 0.2)
        self._driver = robonix_contracts_pb2_grpc.RobonixLifecycleDriverStub(self._channel(endpoint))

    def _channel(self, endpoint: str) -> grpc.Channel:
        ch = grpc.insecure_channel(endpoint)
        self._channels.append(ch)
        return ch

    def endpoint(self, contract_id: str, transport: str) -> str:
        with self.client.connect_capability(consumer_id="slam_test", provider_id=self.name, contract_id=contract_id,
                                            transport=transport) as ch:
            return ch.endpoint

    def _driver_endpoint(self) -> str:
        if self.proc.poll() is not None:
            raise AssertionError(f"{self.name} exited with {self.proc.returncode}:\n{self.log()}")
        if not self.client.find_capability(contract_id=DRIVER, transport="grpc", provider_id=self.name):
            return ""
        return self.endpoint(DRIVER, "grpc")

    def log(self) -> str:
        return self.log_path.read_text(errors="replace")

    def driver(self, command: int, config: dict[str, Any] | None = None) -> tuple[bool, str, str]:
        req = lifecycle_pb2.Driver_Request(command=command, config_json=json.dumps(config or {}))
        resp = self._driver.Driver(req, timeout=120)
        return resp.ok, resp.state, resp.error

    def stub(self, contract_id: str, stub_cls: type) -> Any:
        """A gRPC stub for a contract, found through the atlas (find -> ConnectCapability -> endpoint)."""
        (cap,) = self.client.find_capability(contract_id=contract_id, transport="grpc", provider_id=self.name)
        return stub_cls(self._channel(self.endpoint(cap.contract_id, "grpc")))

    def stop(self) -> int:
        """SIGTERM by PID, SIGKILL after 30 s; returns the exit code and asserts the process is gone."""
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


@pytest.fixture(scope="module")
def atlas() -> Iterator[str]:
    from atlas.server import AtlasServer

    server = AtlasServer(listen="127.0.0.1:0", heartbeat_timeout_ms=60000, eviction_interval_ms=1000)
    address = server.start()
    try:
        yield address
    finally:
        server.stop()


@pytest.fixture(scope="module")
def procs(atlas: str, tmp_path_factory: pytest.TempPathFactory) -> Iterator[Callable[..., Proc]]:
    """``procs(cmd, name, **env)`` starts a provider child; all are stopped (by PID) at module end."""
    started: list[Proc] = []

    def make(cmd: list[str], name: str, **env: str) -> Proc:
        p = Proc(cmd, atlas, name, tmp_path_factory.mktemp(name) / "provider.log", env)
        started.append(p)
        return p

    yield make
    for p in reversed(started):
        if p.proc.poll() is None:
            p.stop()
        assert not alive(p.proc.pid)
