"""The ROS 2 navigate_to_pose action and /goal_pose against real processes (atlas + HAL at rtf 4 + the stand-in
map provider + the navigation provider), driven by a client written to ROS 2's action conventions (raw
rq/rr samples, rosbags payloads: tests/support/ros2_action.py), never through our SDK: a goal SUCCEEDS with
feedback and status on the way, a goal is canceled, /goal_pose starts a run; the runs are the same ones the
gRPC status contract reports (one run_id space)."""

from __future__ import annotations

import time
from collections.abc import Iterator
from typing import Any

import pytest
from support.ros2_action import ActionClient

from robonix_api.dds import DdsNode, PoseStamped
from robonix_api.dds import nav2_action as na
from robonix_api.proto_gen import navigation_pb2 as nav_pb
from robonix_api.proto_gen import robonix_contracts_pb2_grpc as rpc

from .conftest import Proc, start_sim_nav, wait_until

pytestmark = pytest.mark.integration
NS = "robonix/service/navigation/"
KITCHEN, LIVING = (7.0, 1.5), (2.5, 4.0)


@pytest.fixture(scope="module")
def nav(procs) -> Iterator[Proc]:  # type: ignore[no-untyped-def]
    _hal, nav = start_sim_nav(procs, "action")
    yield nav
    assert "Traceback" not in nav.log(), nav.log()[-4000:]


@pytest.fixture
def client() -> Iterator[ActionClient]:
    node = DdsNode(name="ros2_action_client")
    c = ActionClient(node.participant)
    wait_until(lambda: all(len(c.ents[r].get_matched_subscriptions()) >= 1
                           for r in ("send_goal_rq", "get_result_rq", "cancel_rq")), 60, "the action server")
    yield c
    c.close()
    node.close()


def _grpc_status(nav: Proc, run_id: str = "") -> Any:
    stub = nav.stub(NS + "navigate/status", rpc.RobonixServiceNavigationNavigateStatusStub)
    return stub.GetNavigationStatus(nav_pb.GetNavigationStatus_Request(run_id=run_id), timeout=60)


def test_goal_succeeds_with_feedback_and_status(nav: Proc, client: ActionClient) -> None:
    gid = client.uuid()
    reply = client.wait_reply("send_goal_rr", client.send_goal(gid, *KITCHEN), 30)
    assert reply.accepted
    st = _grpc_status(nav)  # the same run, seen through the gRPC contract
    assert st.known
    assert st.state in ("PENDING", "RUNNING")
    result_seq = client.get_result(gid)  # answered only when the goal ends
    result = client.wait_reply("get_result_rr", result_seq, 300)
    assert result.status == na.STATUS_SUCCEEDED, nav.log()[-3000:]
    assert _grpc_status(nav).state == "SUCCEEDED"
    mine = [f for f in client.feedback if bytes(f.goal_id.uuid) == bytes(gid.uuid)]
    assert mine, "no feedback for the goal"
    assert max(f.feedback.distance_remaining for f in mine) > 1.0
    assert mine[-1].feedback.current_pose.header.frame_id == "map"
    uid = bytes(gid.uuid)
    seen = {s.status for a in client.status for s in a.status_list if bytes(s.goal_info.goal_id.uuid) == uid}
    assert {na.STATUS_EXECUTING, na.STATUS_SUCCEEDED} <= seen


def test_cancel_and_goal_pose(nav: Proc, client: ActionClient) -> None:
    gid = client.uuid()
    assert client.wait_reply("send_goal_rr", client.send_goal(gid, *LIVING), 30).accepted
    wait_until(lambda: client.poll() or any(bytes(f.goal_id.uuid) == bytes(gid.uuid) for f in client.feedback),
               60, "feedback of the running goal")
    reply = client.wait_reply("cancel_rr", client.cancel(gid), 30)
    assert reply.return_code == na.CANCEL_ERROR_NONE
    assert [bytes(g.goal_id.uuid) for g in reply.goals_canceling] == [bytes(gid.uuid)]
    assert client.wait_reply("get_result_rr", client.get_result(gid), 30).status == na.STATUS_CANCELED
    assert _grpc_status(nav).state == "CANCELED"
    # cancelling it again: terminated
    assert client.wait_reply("cancel_rr", client.cancel(gid), 30).return_code == na.CANCEL_ERROR_GOAL_TERMINATED

    # RViz2's "2D Goal Pose"
    with DdsNode(name="rviz_like") as node:
        pub = node.create_publisher("/goal_pose", PoseStamped, "reliable")
        assert pub.wait_for_subscribers(1, 30)
        goal = PoseStamped()
        goal.header.frame_id = "map"
        goal.pose.position.x, goal.pose.position.y = LIVING  # far from where the canceled run stopped
        goal.pose.orientation.w = 1.0
        # the reader is best effort, as RViz2's is: a sample sent before the reader has matched this writer
        # (discovery completes on each side separately) is lost, so the goal is re-sent until a run shows
        last_sent = [0.0]

        def new_run() -> object:
            # the latest run was CANCELED: any other state is the new run (it may even have SUCCEEDED already)
            s = _grpc_status(nav)
            if s.state in ("PENDING", "RUNNING", "SUCCEEDED"):
                return s
            if time.monotonic() - last_sent[0] > 3.0:
                pub.publish(goal)
                last_sent[0] = time.monotonic()
            return None

        st = wait_until(new_run, 60,
                        lambda: f"a run started by /goal_pose (latest: {_grpc_status(nav)}); {nav.log()[-2500:]}")
    assert st.known
    assert "/goal_pose: run nav-" in nav.log()
    stub = nav.stub(NS + "navigate/cancel", rpc.RobonixServiceNavigationNavigateCancelStub)
    stub.CancelNavigation(nav_pb.CancelNavigation_Request(run_id=""), timeout=60)

