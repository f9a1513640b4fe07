"""Restarts seen from navigation's side (issue 37 items 1 and 8), without processes:

- TF stamped after the clock (samples of an earlier simulator epoch: a simulator restarted from t = 0) is
  not a pose: navigation must not judge a goal from it (it did, and reported SUCCEEDED 7 m from the robot);
- while a crashed navigation process is being replaced, status of the run it was driving says RUNNING
  "restarting", never a terminal state that later changes;
- ``rbnx navigate`` follows the same run through a restart instead of exiting 1 while the robot drives.
"""

from __future__ import annotations

import threading

import pytest

from nav2_wrapper.config import Frames
from nav2_wrapper.handlers import RESTARTING, NavHandlers
from nav2_wrapper.inputs import Inputs
from rbnx.commands import navigate as nav_cmd
from rbnx.demo.boot import DemoError
from rbnx.demo.rpc import NavStatus
from robonix_api.dds import TfError
from robonix_api.proto_gen import navigation_pb2 as nav_pb


def test_tf_from_an_earlier_clock_epoch_is_not_a_pose() -> None:
    inputs = Inputs(None, {}, Frames(), use_sim_time=True)
    try:
        inputs.tf.set_pose2d("map", "odom", 0.0, 0.0, 0.0, 300.0)
        inputs.tf.set_pose2d("odom", "base_link", 7.0, 1.5, 0.0, 300.0)  # where the old run ended, at t=300
        inputs.clock.set_time(12.0)  # the restarted simulator's clock
        with pytest.raises(TfError, match="after the clock"):
            inputs.robot_state(12.0)
        inputs.tf.clear(keep_static=True)
        inputs.tf.set_pose2d("map", "odom", 0.0, 0.0, 0.0, 12.0)
        inputs.tf.set_pose2d("odom", "base_link", 0.7, 5.4, 0.0, 12.0)
        assert inputs.robot_state(12.0).pose[:2] == pytest.approx((0.7, 5.4))
    finally:
        inputs.close()


def test_status_of_the_run_being_taken_up_after_a_crash_is_running_restarting() -> None:
    h = NavHandlers(lambda: None, lambda: "waiting for CMD_INIT", restarting=lambda: "nav-1234abcd")
    for rid in ("nav-1234abcd", ""):
        r = h.status(nav_pb.GetNavigationStatus_Request(run_id=rid))
        assert (r.known, r.state, r.detail) == (True, "RUNNING", RESTARTING)
        m = h.status_mcp(nav_pb.GetNavigationStatus_Request(run_id=rid))
        assert (m["state"], m["terminal"]) == ("RUNNING", False)
    other = h.status(nav_pb.GetNavigationStatus_Request(run_id="nav-other"))
    assert (other.known, other.state) == (False, "FAILED")  # a run nobody is taking up stays unknown
    first_start = NavHandlers(lambda: None, lambda: "waiting for CMD_INIT")
    r = first_start.status(nav_pb.GetNavigationStatus_Request(run_id="nav-1234abcd"))
    assert r.detail == "not initialized: waiting for CMD_INIT"


class _RestartingRpc:
    """The status contract through a navigation restart: answers, then UNAVAILABLE, then the same run."""

    def __init__(self) -> None:
        self.answers: list[NavStatus | Exception] = [
            NavStatus(True, "RUNNING", "1.0 m left"),
            DemoError("robonix/service/navigation/navigate/status: UNAVAILABLE: connection refused"),
            DemoError("atlas 127.0.0.1:1: cannot resolve robonix/service/navigation/navigate/status: UNAVAILABLE"),
            NavStatus(True, "RUNNING", RESTARTING),
            NavStatus(True, "SUCCEEDED", "reached goal (0.10 m from it)")]
        self.forgotten: list[str] = []

    def status(self, run_id: str) -> NavStatus:
        assert run_id == "nav-1234abcd"
        a = self.answers.pop(0)
        if isinstance(a, Exception):
            raise a
        return a

    def forget(self, contract: str) -> None:
        self.forgotten.append(contract)


class _Instant(threading.Event):
    def wait(self, timeout: float | None = None) -> bool:  # no real sleeping in a unit test
        return False


def test_rbnx_navigate_follows_the_same_run_through_a_restart(capsys: pytest.CaptureFixture[str]) -> None:
    rpc = _RestartingRpc()
    assert nav_cmd._follow(rpc, "nav-1234abcd", _Instant(), 0.0) == 0  # type: ignore[arg-type]
    assert "SUCCEEDED" in capsys.readouterr().out
    assert nav_cmd.STATUS in rpc.forgotten  # looked the restarted provider up again


def test_rbnx_navigate_gives_up_only_after_the_reconnect_window(monkeypatch: pytest.MonkeyPatch) -> None:
    clock = iter(range(0, 10_000, 20))
    monkeypatch.setattr(nav_cmd.time, "monotonic", lambda: float(next(clock)))

    class Gone(_RestartingRpc):
        def status(self, run_id: str) -> NavStatus:
            raise DemoError("status: UNAVAILABLE")

    with pytest.raises(DemoError, match="may still be driving"):
        nav_cmd._follow(Gone(), "nav-1234abcd", _Instant(), 0.0)  # type: ignore[arg-type]
