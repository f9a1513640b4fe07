"""Real processes for the provider tests: an in-process atlas, ``python -m hal_panda_mobile`` as a child.

Every child is stopped by its own PID (SIGTERM, then SIGKILL after a grace period) and the tests assert
it is gone; deadlines are generous because the machine is shared.
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
    """Running and not a zombie (from /proc, no psutil)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat[stat.rfind(")") + 2] not in "ZX"


class HalProcess:
    """One ``python -m hal_panda_mobile`` child registered under ``name``."""

    def __init__(self, atlas: str, name: str, log_path: Path) -> None:
        self.atlas, self.name, self.log_path = atlas, name, log_path
        env = dict(os.environ, ROBONIX_ATLAS=atlas, RBNX_INSTANCE_NAME=name, PYTHONUNBUFFERED="1",
                   ROBONIX_HEARTBEAT_PERIOD_S="2")
        env.pop("RBNX_DEPLOY_MANAGED", None)
        self._log = open(log_path, "w")  # noqa: SIM115 (closed in stop())
        self.proc = subprocess.Popen([sys.executable, "-m", "hal_panda_mobile"], env=env, cwd=REPO,
                                     stdout=self._log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
        self.client = AtlasClient(atlas)
        self.endpoint = wait_until(self._driver_endpoint, 90, f"{name} to declare its driver", 0.2)
        self._channel = grpc.insecure_channel(self.endpoint)
        self._driver = robonix_contracts_pb2_grpc.RobonixLifecycleDriverStub(self._channel)

    def _driver_endpoint(self) -> str:
        if self.proc.poll() is not None:
            raise AssertionError(f"provider exited with {self.proc.returncode}:\n{self.log()}")
        if not self.client.find_capability(contract_id=DRIVER, transport="grpc", provider_id=self.name):
            return ""
        with self.client.connect_capability(consumer_id="hal_test", provider_id=self.name, contract_id=DRIVER,
                                            transport="grpc") as ch:
            return ch.endpoint

    def log(self) -> str:
        return self.log_path.read_text(errors="replace")

    def driver(self, command: int, config: dict[str, Any] | None = None) -> tuple[bool, str, str]:
        req = lifecycle_pb2.Driver_Request(command=command, config_json=json.dumps(config or {}))
        resp = self._driver.Driver(req, timeout=120)
        return resp.ok, resp.state, resp.error

    def init(self, config: dict[str, Any]) -> tuple[bool, str, str]:
        return self.driver(lifecycle_pb2.Driver_Request.CMD_INIT, config)

    def activate(self) -> tuple[bool, str, str]:
        return self.driver(lifecycle_pb2.Driver_Request.CMD_ACTIVATE)

    def deactivate(self) -> tuple[bool, str, str]:
        return self.driver(lifecycle_pb2.Driver_Request.CMD_DEACTIVATE)

    def stub(self, contract_id: str, stub_cls: type) -> Any:
        """A gRPC stub for a contract, found through the atlas (find -> ConnectCapability -> endpoint)."""
        (cap,) = self.client.find_capability(contract_id=contract_id, transport="grpc", provider_id=self.name)
        with self.client.connect_capability(consumer_id="hal_test", provider_id=cap.provider_id,
                                            contract_id=contract_id, transport="grpc") as ch:
            return stub_cls(grpc.insecure_channel(ch.endpoint))

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
        self._channel.close()
        self.client.close()
        self._log.close()
        assert not alive(pid), f"provider pid {pid} still alive"
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
def hal_factory(atlas: str, tmp_path_factory: pytest.TempPathFactory) -> Iterator[Callable[[str], HalProcess]]:
    started: list[HalProcess] = []

    def make(name: str) -> HalProcess:
        p = HalProcess(atlas, name, tmp_path_factory.mktemp(name) / "provider.log")
        started.append(p)
        return p

    yield make
    for p in started:
        if p.proc.poll() is None:
            p.stop()
