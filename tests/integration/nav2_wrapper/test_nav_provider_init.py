"""The provider before and during CMD_INIT: clean "not initialized" answers from process start, Deferred
naming the missing upstream contract, Err naming the bad config field or the missing data."""

from __future__ import annotations

import sys
from collections.abc import Iterator

import pytest

from robonix_api.proto_gen import navigation_pb2 as nav_pb
from robonix_api.proto_gen import robonix_contracts_pb2_grpc as rpc

from .conftest import INIT, MAP_PROVIDER, NAV, SHUTDOWN, Proc, wait_until

pytestmark = pytest.mark.integration
NS = "robonix/service/navigation/"


@pytest.fixture(scope="module")
def nav(procs) -> Iterator[Proc]:  # type: ignore[no-untyped-def]
    p: Proc = procs(NAV, "nav_init")
    yield p
    assert p.stop() == 0
    assert "Traceback" not in p.log(), p.log()[-4000:]


def _goal(x: float = 1.0, y: float = 1.0) -> nav_pb.Navigate_Request:
    req = nav_pb.Navigate_Request()
    req.goal.header.frame_id = "map"
    req.goal.pose.position.x, req.goal.pose.position.y = x, y
    req.goal.pose.orientation.w = 1.0
    return req


def test_contracts_live_before_init(nav: Proc) -> None:
    navigate = nav.stub(NS + "navigate", rpc.RobonixServiceNavigationNavigateStub)
    r = navigate.Navigate(_goal(), timeout=30)
    assert not r.accepted, r.detail
    assert r.detail.startswith("not initialized"), r.detail
    status = nav.stub(NS + "navigate/status", rpc.RobonixServiceNavigationNavigateStatusStub)
    s = status.GetNavigationStatus(nav_pb.GetNavigationStatus_Request(), timeout=30)
    assert (s.known, s.state) == (False, "FAILED")
    assert "not initialized" in s.detail
    cancel = nav.stub(NS + "navigate/cancel", rpc.RobonixServiceNavigationNavigateCancelStub)
    assert not cancel.CancelNavigation(nav_pb.CancelNavigation_Request(), timeout=30).accepted
    speed = nav.stub(NS + "get_speed_limit", rpc.RobonixServiceNavigationGetSpeedLimitStub)
    assert not speed.GetNavigationSpeedLimit(nav_pb.GetNavigationSpeedLimit_Request(), timeout=30).available
    # every contract is declared on the atlas over gRPC and MCP
    for cid in ("navigate", "navigate/status", "navigate/cancel", "adjust_speed", "set_speed_limit",
                "get_speed_limit"):
        wait_until(lambda c=cid: nav.endpoint(NS + c, "grpc") and nav.endpoint(NS + c, "mcp"), 60, cid, 0.2)


def test_invalid_config_names_the_field(nav: Proc) -> None:
    for cfg, field in (({"params_profile": "bogus"}, "params_profile"),
                       ({"dynamic_speed": {"min_percentage": -5}}, "dynamic_speed.min_percentage"),
                       ({"action_wait_s": 0}, "action_wait_s"),
                       ({"topic_remap": {"map": "bad topic"}}, "topic_remap.map"),
                       ({"frobnicate": 1}, "frobnicate"),
                       ({"robot_description": "/nonexistent/robot.yaml"}, "robot_description")):
        ok, state, err = nav.driver(INIT, cfg)
        assert not ok, (cfg, err)
        assert state == "error", (cfg, err)
        assert field in err, (cfg, err)


def test_init_deferred_until_upstream_appears(nav: Proc, procs) -> None:  # type: ignore[no-untyped-def]
    ok, state, err = nav.driver(INIT, {"action_wait_s": 2})
    assert (ok, state) == (False, "deferred")
    assert "robonix/service/map/occupancy_grid" in err, err
    assert "no provider" in err, err
    navigate = nav.stub(NS + "navigate", rpc.RobonixServiceNavigationNavigateStub)
    r = navigate.Navigate(_goal(), timeout=30)
    assert not r.accepted, r.detail
    assert "robonix/service/map/occupancy_grid" in r.detail, r.detail

    procs(MAP_PROVIDER, "map_for_init")  # declares the occupancy grid from process start
    ok, state, err = nav.driver(INIT, {"action_wait_s": 2})
    assert (ok, state) == (False, "deferred"), err
    assert "robonix/primitive/chassis/odom" in err, err
    # a pinned provider that is not there is named
    ok, state, err = nav.driver(INIT, {"action_wait_s": 2, "provider_ids": {"map": "nobody"}})
    assert state == "deferred", err
    assert "'nobody'" in err, err

    # odom remapped (no atlas lookup) but nothing publishes: Err naming each missing input
    ok, state, err = nav.driver(INIT, {"action_wait_s": 2, "topic_remap": {"odom": "/odom_nowhere"}})
    assert (ok, state) == (False, "error"), err
    assert "no /odom_nowhere received within 2 s" in err, err
    assert "no /map received within 2 s" in err, err
    assert "no TF map→odom" in err, err
    r = navigate.Navigate(_goal(), timeout=30)
    assert not r.accepted
    assert "not initialized" in r.detail


def test_package_entry_point_serves_the_same_provider(procs) -> None:  # type: ignore[no-untyped-def]
    """``python -m nav2_wrapper`` is the entry (the fixture above runs the ``atlas_bridge`` alias)."""
    p: Proc = procs([sys.executable, "-m", "nav2_wrapper"], "nav_entry")
    status = p.stub(NS + "navigate/status", rpc.RobonixServiceNavigationNavigateStatusStub)
    s = status.GetNavigationStatus(nav_pb.GetNavigationStatus_Request(), timeout=30)
    assert (s.known, s.state) == (False, "FAILED"), s.detail
    assert s.detail == "not initialized: waiting for CMD_INIT", s.detail
    assert p.stop() == 0, p.log()[-4000:]
    assert "Traceback" not in p.log(), p.log()[-4000:]


def test_shutdown(nav: Proc) -> None:
    assert nav.driver(SHUTDOWN)[:2] == (True, "terminated")
    nav.proc.wait(60)
    assert nav.proc.returncode == 0
