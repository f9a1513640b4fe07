"""Issue 15 acceptance: two deployments of the same sim deploy file run side by side on one host (own
atlas ports and DDS domains, but the same state dir and run-dir base, as two users of one machine would
have); `rbnx shutdown` of one leaves every process of the other running and its goal still succeeds.

Before deployments were keyed, both shared the state file of the deploy path and nav2's pidfile
(`<run dir>/nav2-nav2.pid`), so stopping one SIGTERMed the other's navigation.
"""

from __future__ import annotations

import json
import signal
import socket
import subprocess
from pathlib import Path

import pytest
from support.e2e import SIM_DEPLOY, e2e_env, navigate, rbnx_cmd, recorded_pids, wait_until

from rbnx.boot.statefile import state_path
from rbnx.demo.boot import pick_domain_id
from robonix_api.procs import pid_alive

pytestmark = [pytest.mark.integration, pytest.mark.slow, pytest.mark.timeout(420)]
KITCHEN_GOAL = (5.8, 3.0)  # the kitchen's island_east waypoint, 2.9 m from the start pose


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Deployment:
    """One `rbnx boot` of the sim deploy with its own atlas port and ROS domain."""

    def __init__(self, tmp: Path, name: str, domain: int) -> None:
        self.listen = f"127.0.0.1:{_free_port()}"
        shared = {"RBNX_STATE_DIR": str(tmp / "state"), "XDG_RUNTIME_DIR": str(tmp / "xdg")}
        self.env = e2e_env(tmp, RBNX_SIM_SCENE="kitchen", RBNX_SIM_RTF="2", RBNX_ATLAS_LISTEN=self.listen,
                           ROS_DOMAIN_ID=str(domain), **shared)
        self.env.pop("RBNX_RUN_DIR", None)
        self.out = tmp / f"{name}.out"
        self.logs = tmp / f"{name}-logs"
        with open(self.out, "w") as fh:
            self.proc = subprocess.Popen(rbnx_cmd() + ["boot", "-f", str(SIM_DEPLOY), "--no-progress",
                                                       "--log-dir", str(self.logs)],
                                         env=self.env, cwd=tmp, stdout=fh, stderr=subprocess.STDOUT,
                                         stdin=subprocess.DEVNULL)

    @property
    def state_file(self) -> Path:
        return Path(self.env["RBNX_STATE_DIR"]) / state_path(SIM_DEPLOY, self.listen).name

    def booted(self) -> bool:
        if self.proc.poll() is not None:
            raise AssertionError(f"rbnx boot exited {self.proc.returncode}:\n{self.out.read_text()}")
        return "3/3 entries ready" in self.out.read_text()

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
            try:
                self.proc.wait(90)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(30)


def test_shutdown_of_one_deployment_leaves_the_other_running(tmp_path: Path) -> None:
    domain_a = domain_b = pick_domain_id()
    while domain_b == domain_a:
        domain_b = pick_domain_id()
    a = Deployment(tmp_path, "a", domain_a)
    b = Deployment(tmp_path, "b", domain_b)
    try:
        wait_until(lambda: a.booted() and b.booted(), 240, "both deployments to boot (3/3 entries ready)")
        assert a.state_file != b.state_file
        assert a.state_file.is_file()
        assert b.state_file.is_file()
        pids_a, pids_b = recorded_pids(a.state_file), recorded_pids(b.state_file)
        assert {n for n, _, _ in pids_b} >= {"rbnx boot", "atlas", "panda_mobile", "mapping", "nav2"}
        run_dirs = sorted((tmp_path / "xdg" / "robonix").iterdir())
        assert len(run_dirs) == 2, run_dirs  # one run dir (and nav2 pidfile) per deployment
        assert all((d / "nav2-nav2.pid").is_file() for d in run_dirs)

        down = subprocess.run(rbnx_cmd() + ["shutdown", "-f", str(SIM_DEPLOY), "--term-timeout", "20"],
                              env=a.env, cwd=tmp_path, capture_output=True, text=True, timeout=240)
        assert down.returncode == 0, down.stdout + down.stderr
        assert a.proc.wait(120) == 0, a.out.read_text()
        wait_until(lambda: not [p for p in pids_a if pid_alive(p[1], p[2])], 60, "every process of A to exit")

        gone_b = [p for p in pids_b if not pid_alive(p[1], p[2])]
        assert not gone_b, f"stopping A took down B's {gone_b}"
        assert b.state_file.is_file()
        assert "exited on its own" not in b.out.read_text(), b.out.read_text()

        state, detail, _ = navigate(b.env["RBNX_ATLAS_LISTEN"], *KITCHEN_GOAL, timeout_s=120,
                                    token=json.loads(b.state_file.read_text()).get("token", ""))
        assert state == "SUCCEEDED", detail
        assert all(pid_alive(p[1], p[2]) for p in pids_b)

        b.proc.send_signal(signal.SIGINT)
        assert b.proc.wait(120) == 0, b.out.read_text()
        wait_until(lambda: not [p for p in pids_b if pid_alive(p[1], p[2])], 60, "every process of B to exit")
    finally:
        a.stop()
        b.stop()
