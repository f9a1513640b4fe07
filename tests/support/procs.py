"""Provider child processes for the integration tests and the latency bench: start ``python -m <provider>``
registered under a name, find it through the atlas, drive its lifecycle Driver, stop it by PID (SIGTERM,
SIGKILL after a grace period) and check that nothing is left behind. No pytest in here (the bench uses it).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import grpc

from robonix_api.atlas_client import AtlasClient
from robonix_api.procs import stop_process
from robonix_api.proto_gen import lifecycle_pb2, robonix_contracts_pb2_grpc

from .wait import wait_until  # also imported from here by the tests and bench/nav_latency_bench.py

DRIVER = "robonix/lifecycle/driver"
REPO = Path(__file__).resolve().parents[2]
HAL = [sys.executable, "-m", "hal_panda_mobile"]
SLAM = [sys.executable, "-m", "slam_service"]
NAV = [sys.executable, "-m", "nav2_wrapper.atlas_bridge"]
# the stand-in map service of the navigation tests
MAP_PROVIDER = [sys.executable, str(REPO / "tests" / "integration" / "nav2_wrapper" / "map_provider.py")]
INIT, ACTIVATE, DEACTIVATE, SHUTDOWN = 0, 1, 2, 3


def alive(pid: int) -> bool:
    """Running and not a zombie (from /proc, no psutil)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat[stat.rfind(")") + 2] not in "ZX"


class Proc:
    """One provider child registered under ``name``; ``driver()`` speaks its lifecycle Driver.

    The constructor launches the process and, if ``wait_ready``, waits for its Driver on the atlas;
    otherwise call ``ready()`` (so several children can be launched first and their imports overlap).
    Subclasses tune the class attributes below.
    """

    consumer_id = "nav_test"    # who asks the atlas for the endpoints
    wait_ready = True           # wait for the Driver in the constructor
    ready_timeout_s = 120.0     # for the Driver to be declared
    driver_timeout_s = 180.0    # per Driver call
    init_retry_s = 0.0          # how long init() retries while CMD_INIT answers Deferred

    def __init__(self, cmd: list[str], atlas: str, name: str, log_path: Path,
                 env: dict[str, str] | None = None) -> None:
        self.atlas, self.name, self.log_path = atlas, name, log_path
        full_env = dict(os.environ, ROBONIX_ATLAS=atlas, RBNX_INSTANCE_NAME=name, PYTHONUNBUFFERED="1",
                        ROBONIX_HEARTBEAT_PERIOD_S="2", **(env or {}))
        full_env.pop("RBNX_DEPLOY_MANAGED", None)
        self._log = open(log_path, "w")  # noqa: SIM115 (closed in stop())
        self.proc = subprocess.Popen(cmd, env=full_env, cwd=REPO, stdout=self._log, stderr=subprocess.STDOUT,
                                     stdin=subprocess.DEVNULL)
        self.client = AtlasClient(atlas)
        self._channels: list[grpc.Channel] = []
        self._driver: Any = None
        if self.wait_ready:
            self.ready()

    def ready(self, timeout_s: float | None = None) -> Proc:
        """Wait (``ready_timeout_s`` by default) for the Driver on the atlas and connect to it."""
        timeout_s = self.ready_timeout_s if timeout_s is None else timeout_s
        endpoint = wait_until(lambda: self.endpoint(DRIVER), timeout_s, f"{self.name} to declare its driver", 0.2)
        self._driver = robonix_contracts_pb2_grpc.RobonixLifecycleDriverStub(self._channel(endpoint))
        return self

    def _channel(self, endpoint: str) -> grpc.Channel:
        ch = grpc.insecure_channel(endpoint)
        self._channels.append(ch)
        return ch

    def endpoint(self, contract_id: str, transport: str = "grpc") -> str:
        """The endpoint of a contract found through the atlas (find → ConnectCapability), "" if not declared."""
        if self.proc.poll() is not None:
            raise AssertionError(f"{self.name} exited with {self.proc.returncode}:\n{self.log()[-4000:]}")
        if not self.client.find_capability(contract_id=contract_id, transport=transport, provider_id=self.name):
            return ""
        with self.client.connect_capability(consumer_id=self.consumer_id, provider_id=self.name,
                                            contract_id=contract_id, transport=transport) as ch:
            return ch.endpoint

    def stub(self, contract_id: str, stub_cls: type) -> Any:
        """A gRPC stub for a contract found through the atlas (find → ConnectCapability → endpoint)."""
        endpoint = self.endpoint(contract_id)
        assert endpoint, f"{self.name} declares no {contract_id} over grpc"
        return stub_cls(self._channel(endpoint))

    def log(self) -> str:
        return self.log_path.read_text(errors="replace")

    def driver(self, command: int, config: dict[str, Any] | None = None) -> tuple[bool, str, str]:
        req = lifecycle_pb2.Driver_Request(command=command, config_json=json.dumps(config or {}))
        resp = self._driver.Driver(req, timeout=self.driver_timeout_s)
        return resp.ok, resp.state, resp.error

    def init(self, config: dict[str, Any], timeout_s: float | None = None) -> tuple[bool, str, str]:
        """CMD_INIT; while it answers Deferred, retried with a short back-off for ``timeout_s`` (default
        ``init_retry_s``) — what ``rbnx boot`` does."""
        deadline = time.monotonic() + (self.init_retry_s if timeout_s is None else timeout_s)
        while True:
            ok, state, err = self.driver(INIT, config)
            if state != "deferred" or time.monotonic() >= deadline:
                return ok, state, err
            time.sleep(0.5)

    def activate(self) -> tuple[bool, str, str]:
        return self.driver(ACTIVATE)

    def deactivate(self) -> tuple[bool, str, str]:
        return self.driver(DEACTIVATE)

    def stop(self) -> int:
        """SIGTERM by PID, SIGKILL after 30 s; asserts the process is gone and returns its exit code.
        Safe to call again."""
        pid = self.proc.pid
        stop_process(self.proc, 30.0)
        for ch in self._channels:
            ch.close()
        self._channels.clear()
        self.client.close()
        if not self._log.closed:
            self._log.close()
        assert not alive(pid), f"{self.name} pid {pid} still alive"
        return self.proc.returncode


def stop_all(started: Iterable[Proc], *, clean_exit: bool = False) -> dict[str, int]:
    """Stop every child in the given order (by PID), assert none is left behind and, with ``clean_exit``,
    that each exited 0; returns the exit codes by name."""
    started = list(started)
    codes = {p.name: p.stop() for p in started}
    left = [(p.name, p.proc.pid) for p in started if alive(p.proc.pid)]
    assert not left, f"processes left behind: {left}"
    if clean_exit:
        assert all(c == 0 for c in codes.values()), f"unclean exits: {codes}"
    return codes
