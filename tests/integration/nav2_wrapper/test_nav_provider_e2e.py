"""End to end with real processes: atlas + HAL (MuJoCo, sim time at rtf 4) + the stand-in map provider +
the navigation provider. Goals go over gRPC (and MCP) to the contracts found through the atlas; the
outcome is judged on the HAL's ground truth, never on the navigator's own belief."""

from __future__ import annotations

import asyncio
import math
from collections.abc import Iterator
from typing import Any

import pytest

from robonix_api.dds import DdsNode
from robonix_api.dds import Path as PathMsg
from robonix_api.proto_gen import navigation_pb2 as nav_pb
from robonix_api.proto_gen import robonix_contracts_pb2_grpc as rpc
from robonix_api.proto_gen import sim_pb2

from .conftest import ACTIVATE, DEACTIVATE, Proc, start_sim_nav, wait_until

pytestmark = pytest.mark.integration
NS = "robonix/service/navigation/"
SIM = "robonix/primitive/sim/"
KITCHEN, BEDROOM_2, LIVING = (7.0, 1.5), (7.0, 6.5), (2.5, 4.0)


class System:
    def __init__(self, hal: Proc, nav: Proc) -> None:
        self.hal, self.nav = hal, nav
        self.navigate_stub = nav.stub(NS + "navigate", rpc.RobonixServiceNavigationNavigateStub)
        self.status_stub = nav.stub(NS + "navigate/status", rpc.RobonixServiceNavigationNavigateStatusStub)
        self.cancel_stub = nav.stub(NS + "navigate/cancel", rpc.RobonixServiceNavigationNavigateCancelStub)
        self.gt_stub = hal.stub(SIM + "ground_truth", rpc.RobonixPrimitiveSimGroundTruthStub)
        self.coll_stub = hal.stub(SIM + "collisions", rpc.RobonixPrimitiveSimCollisionsStub)

    def navigate(self, x: float, y: float, frame: str = "map", q: tuple[float, ...] = (0, 0, 0, 1)) -> Any:
        req = nav_pb.Navigate_Request()
        req.goal.header.frame_id = frame
        req.goal.pose.position.x, req.goal.pose.position.y = x, y
        o = req.goal.pose.orientation
        o.x, o.y, o.z, o.w = q
        return self.navigate_stub.Navigate(req, timeout=60)

    def status(self, run_id: str = "") -> Any:
        return self.status_stub.GetNavigationStatus(nav_pb.GetNavigationStatus_Request(run_id=run_id), timeout=60)

    def cancel(self, run_id: str = "") -> Any:
        return self.cancel_stub.CancelNavigation(nav_pb.CancelNavigation_Request(run_id=run_id), timeout=60)

    def gt(self) -> Any:
        return self.gt_stub.GetGroundTruth(sim_pb2.GetGroundTruth_Request(), timeout=60)

    def speed(self) -> float:
        g = self.gt()
        return math.hypot(g.vx, g.vy)

    def wait_state(self, run_id: str, states: tuple[str, ...], timeout_s: float) -> Any:
        return wait_until(lambda: (s := self.status(run_id)).state in states and s, timeout_s,
                          f"{run_id} to reach {states} (now {self.status(run_id).state}: {self.status(run_id).detail})",
                          0.2)


@pytest.fixture(scope="module")
def system(procs) -> Iterator[System]:  # type: ignore[no-untyped-def]
    hal, nav = start_sim_nav(procs, "e2e")
    yield System(hal, nav)
    log = nav.log()
    assert "Traceback" not in log, log[-4000:]
    assert "loop iteration failed" not in log, log[-4000:]


@pytest.mark.slow  # a long live-sim drive: the slow suite of .ci/run
def test_navigate_to_reachable_goal(system: System) -> None:
    t0 = system.gt().sim_time
    node = DdsNode(name="nav_test")
    plans: list[Any] = []
    sub = node.create_subscription("/plan", PathMsg, plans.append, "reliable")
    try:
        r = system.navigate(*KITCHEN)
        assert r.accepted, r.detail
        assert r.run_id, r.detail
        s = system.wait_state(r.run_id, ("SUCCEEDED", "FAILED", "CANCELED"), 240)
        assert s.state == "SUCCEEDED", (s.detail, system.nav.log()[-3000:])
    finally:
        sub.close()
        node.close()
    g = system.gt()
    assert math.hypot(g.x - KITCHEN[0], g.y - KITCHEN[1]) < 0.35, (g.x, g.y)
    assert abs(math.remainder(g.theta, 2 * math.pi)) < 0.35
    assert system.coll_stub.GetCollisions(sim_pb2.GetCollisions_Request(since_sim_time=t0), timeout=60).count == 0
    assert plans
    assert plans[0].header.frame_id == "map"
    assert len(plans[0].poses) > 2
    assert wait_until(lambda: system.speed() < 0.02, 30, "the base to rest")


def test_bad_goals_rejected_with_reason(system: System) -> None:
    cases = [
        (dict(x=float("nan"), y=1.0), "position.x: non-finite"),
        (dict(x=3.0, y=4.0, frame="no_such_frame"), "unknown frame 'no_such_frame'"),
        (dict(x=3.0, y=4.0, q=(0, 0, 0, 0.5)), "quaternion not normalised (norm 0.5)"),
        (dict(x=2.5, y=2.0), "inside an obstacle"),          # the coffee table
        (dict(x=50.0, y=50.0), "off the map"),
    ]
    for kwargs, reason in cases:
        r = system.navigate(**kwargs)
        assert not r.accepted, (kwargs, r.detail)
        assert reason in r.detail, (kwargs, r.detail)
        s = system.status(r.run_id)
        assert s.known
        assert s.state == "FAILED"
        assert reason in s.detail
    # a goal in another TF frame connected to map (odom; identity here) is transformed, not rejected
    r = system.navigate(3.0, 4.0, frame="odom")
    assert r.accepted, r.detail
    assert "goal (3.00, 4.00" in r.detail, r.detail
    assert system.cancel(r.run_id).accepted
    t_cancel = system.gt().sim_time
    unknown = system.status("nav-doesnotexist")
    assert (unknown.known, unknown.state) == (False, "FAILED")
    # Under load the base may already be moving when cancel lands: stopped within 0.5 s of sim time.
    g = wait_until(lambda: (x := system.gt()).sim_time >= t_cancel + 0.5 and x, 60, "0.5 s of sim time", 0.02)
    assert math.hypot(g.vx, g.vy) < 0.03, (g.vx, g.vy, g.wz)
    assert abs(g.wz) < 0.05, (g.vx, g.vy, g.wz)


@pytest.mark.slow  # a long live-sim drive: the slow suite of .ci/run
def test_preempt_then_cancel_stops_the_base(system: System) -> None:
    first = system.navigate(*BEDROOM_2)
    assert first.accepted, first.detail
    system.wait_state(first.run_id, ("RUNNING",), 120)
    second = system.navigate(*LIVING)
    assert second.accepted
    assert f"preempted {first.run_id}" in second.detail
    s = system.status(first.run_id)
    assert s.state == "CANCELED"
    assert f"preempted by {second.run_id}" in s.detail
    wait_until(lambda: system.status(second.run_id).state == "RUNNING" and system.speed() > 0.15, 120,
               "the second goal to drive the base", 0.1)
    c = system.cancel()
    t_cancel = system.gt().sim_time
    assert c.accepted, c.detail
    assert system.status(second.run_id).state == "CANCELED"
    g = wait_until(lambda: (x := system.gt()).sim_time >= t_cancel + 0.5 and x, 60, "0.5 s of sim time", 0.02)
    assert math.hypot(g.vx, g.vy) < 0.03, (g.vx, g.vy, g.wz)
    assert abs(g.wz) < 0.05, (g.vx, g.vy, g.wz)
    again = system.cancel(second.run_id)
    assert not again.accepted
    assert "already CANCELED" in again.detail


def test_speed_contracts(system: System) -> None:
    nav = system.nav
    get = nav.stub(NS + "get_speed_limit", rpc.RobonixServiceNavigationGetSpeedLimitStub)
    set_ = nav.stub(NS + "set_speed_limit", rpc.RobonixServiceNavigationSetSpeedLimitStub)
    adjust = nav.stub(NS + "adjust_speed", rpc.RobonixServiceNavigationAdjustSpeedStub)
    g = get.GetNavigationSpeedLimit(nav_pb.GetNavigationSpeedLimit_Request(), timeout=60)
    assert g.available
    assert g.max_linear_speed_mps == pytest.approx(0.5)
    assert g.effective_percentage == 100
    r = set_.SetNavigationSpeedLimit(nav_pb.SetNavigationSpeedLimit_Request(percentage=50, persist=True), timeout=60)
    assert r.accepted
    assert r.changed
    assert r.scope == "session"
    assert r.effective_linear_speed_mps == pytest.approx(0.25)
    r = adjust.AdjustNavigationSpeed(nav_pb.AdjustNavigationSpeed_Request(direction="slower", persist=True),
                                     timeout=60)
    assert r.accepted
    assert r.effective_percentage == pytest.approx(40)
    r = set_.SetNavigationSpeedLimit(nav_pb.SetNavigationSpeedLimit_Request(percentage=5, persist=True), timeout=60)
    assert not r.accepted
    assert "percentage" in r.detail
    r = adjust.AdjustNavigationSpeed(nav_pb.AdjustNavigationSpeed_Request(direction="sideways"), timeout=60)
    assert not r.accepted
    assert "direction" in r.detail
    r = adjust.AdjustNavigationSpeed(nav_pb.AdjustNavigationSpeed_Request(direction="normal", persist=True),
                                     timeout=60)
    assert r.accepted
    assert r.effective_percentage == 100


def test_deactivate_rejects_goals(system: System) -> None:
    assert system.nav.driver(DEACTIVATE)[:2] == (True, "inactive")
    r = system.navigate(*LIVING)
    assert not r.accepted, r.detail
    assert r.detail.startswith("inactive"), r.detail
    assert system.nav.driver(ACTIVATE)[:2] == (True, "active")


def test_mcp_navigate_status_cancel(system: System) -> None:
    from mcp import Client

    url = system.nav.endpoint(NS + "navigate", "mcp")

    def goal(x: float, y: float) -> dict[str, Any]:
        return {"goal": {"header": {"frame_id": "map"},
                         "pose": {"position": {"x": x, "y": y}, "orientation": {"w": 1.0}}}}

    async def talk() -> dict[str, Any]:
        out: dict[str, Any] = {}
        async with Client(url) as c:
            out["tools"] = {t.name for t in (await c.list_tools()).tools}
            r = (await c.call_tool("navigate", goal(3.5, 4.5))).structured_content
            assert r["accepted"], r
            seen_running = None
            for _ in range(1200):
                st = (await c.call_tool("status", {"run_id": r["run_id"]})).structured_content
                if st["state"] == "RUNNING" and st["distance_remaining_m"] is not None:
                    seen_running = seen_running or st
                if st["terminal"]:
                    break
                await asyncio.sleep(0.2)
            out["first"], out["running"] = st, seen_running
            r2 = (await c.call_tool("navigate", goal(*BEDROOM_2))).structured_content
            for _ in range(600):
                st = (await c.call_tool("status", {})).structured_content
                if st["state"] == "RUNNING":
                    break
                await asyncio.sleep(0.2)
            out["cancel"] = (await c.call_tool("cancel", {"run_id": r2["run_id"]})).structured_content
            out["after"] = (await c.call_tool("status", {"run_id": r2["run_id"]})).structured_content
            out["unknown"] = (await c.call_tool("status", {"run_id": "nope"})).structured_content
        return out

    out = asyncio.run(asyncio.wait_for(talk(), 400))
    assert {"navigate", "status", "cancel", "adjust_speed", "set_speed_limit", "get_speed_limit"} <= out["tools"]
    assert out["first"]["state"] == "SUCCEEDED", out["first"]
    assert out["running"]
    assert out["running"]["goal"]["x"] == 3.5
    assert out["running"]["recoveries"] >= 0
    assert out["cancel"]["accepted"]
    assert out["after"]["state"] == "CANCELED"
    assert out["unknown"]["known"] is False
    assert out["unknown"]["state"] == "FAILED"


def test_losing_the_chassis_fails_the_run(system: System) -> None:
    r = system.navigate(*KITCHEN)
    assert r.accepted
    system.wait_state(r.run_id, ("RUNNING",), 120)
    assert system.hal.stop() == 0           # odometry, TF and /clock all stop
    s = system.wait_state(r.run_id, ("FAILED",), 60)
    assert any(k in s.detail for k in ("/clock stalled", "odometry", "left the atlas")), s.detail
