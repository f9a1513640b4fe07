"""Helpers of the fault tests: a real `rbnx boot` of the sim deploy that the test then hurts (and that
must still shut down cleanly, leaving no process of any run), a navigate call that rides out a busy
provider's slow status replies, and adopting a boot's deployment token (the SDK's and rbnx's clients
send ``$ROBONIX_DEPLOY_TOKEN``)."""

from __future__ import annotations

import json
import subprocess
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import grpc
import pytest
from support.e2e import SIM_DEPLOY, e2e_env, grpc_endpoint, rbnx_cmd, recorded_pids
from support.procs import wait_until

from robonix_api import auth
from robonix_api.atlas_client import AtlasClient
from robonix_api.procs import pid_alive
from robonix_api.proto_gen import navigation_pb2
from robonix_api.proto_gen import robonix_contracts_pb2_grpc as stubs


def navigate(atlas: str, x: float, y: float, timeout_s: float, accept_within_s: float = 10.0) -> tuple[str, str]:
    """Send a goal over gRPC and wait for its end; a status call that times out (a just-restarted process
    still warming up on a loaded machine) is asked again, not taken as the answer. A goal rejected because
    an upstream "left the atlas" is sent again for ``accept_within_s``: navigation re-checks its
    upstreams every 2 s, so right after a restart it may not have seen the new provider yet."""
    with AtlasClient(atlas) as client:
        nav_ep = grpc_endpoint(client, "robonix/service/navigation/navigate")
        status_ep = grpc_endpoint(client, "robonix/service/navigation/navigate/status")
    req = navigation_pb2.Navigate_Request()
    req.goal.header.frame_id = "map"
    req.goal.pose.position.x, req.goal.pose.position.y = x, y
    req.goal.pose.orientation.w = 1.0
    with auth.channel(nav_ep) as nav_ch, auth.channel(status_ep) as st_ch:
        nav = stubs.RobonixServiceNavigationNavigateStub(nav_ch)

        def accepted() -> navigation_pb2.Navigate_Response | None:
            r = nav.Navigate(req, timeout=30)
            assert r.accepted or "left the atlas" in r.detail, r.detail
            return r if r.accepted else None

        resp = wait_until(accepted, accept_within_s, "navigation to accept the goal", 0.25)
        status = stubs.RobonixServiceNavigationNavigateStatusStub(st_ch)

        def terminal() -> navigation_pb2.GetNavigationStatus_Response | None:
            try:
                st = status.GetNavigationStatus(navigation_pb2.GetNavigationStatus_Request(run_id=resp.run_id),
                                                timeout=10)
            except grpc.RpcError as exc:
                if exc.code() == grpc.StatusCode.DEADLINE_EXCEEDED:
                    return None
                raise
            return st if st.state in ("SUCCEEDED", "FAILED", "CANCELED") else None

        st = wait_until(terminal, timeout_s, f"goal {resp.run_id} to finish", 0.5)
    return st.state, st.detail


def adopt_token(state_file: Path, monkeypatch: pytest.MonkeyPatch) -> str:
    """This test acts as a client of the deployment: its token for the test's duration."""
    token = str(json.loads(state_file.read_text()).get("token") or "")
    if token:
        monkeypatch.setenv("ROBONIX_DEPLOY_TOKEN", token)
    return token


@dataclass
class SimBoot:
    """A booted sim deployment: its process, output file, state file, atlas address and environment."""

    proc: subprocess.Popen[bytes]
    out: Path
    state_file: Path
    atlas: str
    env: dict[str, str]
    every_pid: set[tuple[str, int, int | None]] = field(default_factory=set)

    def record_pids(self) -> None:
        """Remember every process the boot has recorded so far (restarted ones included)."""
        self.every_pid.update(recorded_pids(self.state_file))

    def output(self) -> str:
        return self.out.read_text()

    def state(self) -> dict:
        return json.loads(self.state_file.read_text())


@contextmanager
def booted(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, deploy: Path, entries: int, env: dict[str, str],
           *options: str) -> Iterator[SimBoot]:
    """`rbnx boot -f deploy --no-gateway` until ``entries`` entries are ready (``options`` go to the boot);
    on leaving: SIGINT, exit code 0, and no process of any run (first or restarted) left alive."""
    out = tmp_path / "boot.out"
    with open(out, "w") as fh:
        proc = subprocess.Popen(rbnx_cmd() + ["boot", "-f", str(deploy), *options, "--no-gateway",
                                              "--log-dir", str(tmp_path / "logs")],
                                env=env, cwd=tmp_path, stdout=fh, stderr=subprocess.STDOUT,
                                stdin=subprocess.DEVNULL)
    every_pid: set[tuple[str, int, int | None]] = set()
    try:
        def ready() -> bool:
            if proc.poll() is not None:
                raise AssertionError(f"rbnx boot exited {proc.returncode}:\n{out.read_text()}")
            return f"{entries}/{entries} entries ready" in out.read_text()

        wait_until(ready, 150, f"the boot summary ({entries}/{entries} entries ready)")
        (state_file,) = (tmp_path / "state").glob("boot-*.json")
        adopt_token(state_file, monkeypatch)
        run = SimBoot(proc, out, state_file, json.loads(state_file.read_text())["atlas"], env, every_pid)
        run.record_pids()
        yield run
    finally:
        if proc.poll() is None:
            proc.send_signal(2)
            try:
                proc.wait(120)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait(10)
    assert proc.returncode == 0, out.read_text()[-3000:]
    wait_until(lambda: not any(pid_alive(p, t) for _, p, t in every_pid), 30, "every process of every run to exit")


@contextmanager
def sim_boot(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, **env: str) -> Iterator[SimBoot]:
    """examples/sim/deploy.yaml (kitchen, RTF 2, no progress view) booted until its 3 entries are ready."""
    full_env = e2e_env(tmp_path, RBNX_SIM_SCENE="kitchen", RBNX_SIM_RTF="2", **env)
    with booted(tmp_path, monkeypatch, SIM_DEPLOY, 3, full_env, "--no-progress") as run:
        yield run
