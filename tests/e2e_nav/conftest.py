"""Real processes for the navigation acceptance tests: an in-process atlas plus HAL, SLAM and nav children.

Every child is found through the atlas like any consumer would find it, driven over its lifecycle Driver
and stopped by its own PID (SIGTERM, SIGKILL after a grace period); the fixtures assert none is left.
The children are launched together and only then awaited, so their (heavy) imports overlap. Deadlines
are generous: the machine is shared and has two cores. Helpers are copied from tests/nav_provider and
tests/slam_provider on purpose (test directories do not import each other).
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
HAL = [sys.executable, "-m", "hal_panda_mobile"]
SLAM = [sys.executable, "-m", "slam_service"]
NAV = [sys.executable, "-m", "nav2_wrapper.atlas_bridge"]
INIT, ACTIVATE, DEACTIVATE, SHUTDOWN = 0, 1, 2, 3


def wait_until(pred: Callable[[], Any], timeout_s: float, what: str | Callable[[], str],
               interval: float = 0.1) -> Any:
    """Poll ``pred`` until truthy; ``what`` (or its result) explains a timeout."""
    deadline = time.monotonic() + timeout_s
    while True:
        value = pred()
        if value:
            return value
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout_s} s waiting for {what() if callable(what) else what}")
        time.sleep(interval)


def alive(pid: int) -> bool:
    """Running and not a zombie (from /proc, no psutil)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat[stat.rfind(")") + 2] not in "ZX"


class Proc:
    """One provider child registered under ``name``; ``driver()`` speaks its lifecycle Driver.

    The constructor only launches the process; ``ready()`` waits for its Driver on the atlas.
    """

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
        self._driver: Any = None

    def ready(self, timeout_s: float = 120) -> Proc:
        endpoint = wait_until(lambda: self.endpoint(DRIVER), timeout_s, f"{self.name} to declare its driver", 0.2)
        self._driver = robonix_contracts_pb2_grpc.RobonixLifecycleDriverStub(self._channel(endpoint))
        return self

    def _channel(self, endpoint: str) -> grpc.Channel:
        ch = grpc.insecure_channel(endpoint)
        self._channels.append(ch)
        return ch

    def endpoint(self, contract_id: str, transport: str = "grpc") -> str:
        if self.proc.poll() is not None:
            raise AssertionError(f"{self.name} exited with {self.proc.returncode}:\n{self.log()[-4000:]}")
        if not self.client.find_capability(contract_id=contract_id, transport=transport, provider_id=self.name):
            return ""
        with self.client.connect_capability(consumer_id="e2e_nav_test", provider_id=self.name,
                                            contract_id=contract_id, transport=transport) as ch:
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

    def init(self, config: dict[str, Any], timeout_s: float = 90) -> tuple[bool, str, str]:
        """CMD_INIT, retried with a short back-off while it answers Deferred — what ``rbnx boot`` does."""
        deadline = time.monotonic() + timeout_s
        while True:
            ok, state, err = self.driver(INIT, config)
            if state != "deferred" or time.monotonic() > deadline:
                return ok, state, err
            time.sleep(0.5)

    def stop(self) -> int:
        """SIGTERM by PID, SIGKILL after 30 s; asserts the process is gone and returns its exit code."""
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
        self._channels.clear()
        self.client.close()
        if not self._log.closed:
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
    """``procs(cmd, name, **env)`` launches a provider child; all are stopped (by PID, newest first) at the end."""
    started: list[Proc] = []

    def make(cmd: list[str], name: str, **env: str) -> Proc:
        p = Proc(cmd, atlas, name, tmp_path_factory.mktemp(name) / "provider.log", env)
        started.append(p)
        return p

    yield make
    codes = {p.name: p.stop() for p in reversed(started)}   # SIGTERM by PID; a clean shutdown exits 0
    left = [(p.name, p.proc.pid) for p in started if alive(p.proc.pid)]
    assert not left, f"processes left behind: {left}"
    assert all(c == 0 for c in codes.values()), f"unclean exits: {codes}"
