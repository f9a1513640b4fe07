"""The NavigateToPose action's wire structs against rosbags types built from navigation2's Humble .action
definition: our bytes decode with rosbags and rosbags' bytes decode with ours, for every service sample
(header + fields) and both topics."""

from __future__ import annotations

from support.ros2_action import PKG, action_store, from_service_bytes, to_service_bytes

from robonix_api.dds import nav2_action as na
from robonix_api.dds.messages import Time

STORE = action_store()
GUID, SEQ = 0x1122334455667788, 42
UID = bytes(range(16))  # uint8[16] comes back as bytes


def test_send_goal_request_round_trips() -> None:
    ours = na.SendGoalRequestWire(GUID, SEQ, na.UUID(UID))
    ours.goal.pose.header.frame_id = "map"
    ours.goal.pose.pose.position.x, ours.goal.pose.pose.position.y = 7.0, -1.5
    ours.goal.pose.pose.orientation.w = 1.0
    ours.goal.behavior_tree = "bt.xml"
    guid, seq, msg = from_service_bytes(STORE, f"{PKG}SendGoal_Request", ours.serialize())
    assert (guid, seq) == (GUID, SEQ)
    assert bytes(msg.goal_id.uuid) == UID
    assert (msg.goal.pose.header.frame_id, msg.goal.pose.pose.position.x, msg.goal.pose.pose.position.y) == (
        "map", 7.0, -1.5)
    assert msg.goal.behavior_tree == "bt.xml"
    back = na.SendGoalRequestWire.deserialize(to_service_bytes(STORE, f"{PKG}SendGoal_Request", msg, GUID, SEQ))
    assert back == ours


def test_replies_and_cancel_round_trip() -> None:
    cases = [
        (na.SendGoalResponseWire(GUID, SEQ, True, Time(5, 6)), f"{PKG}SendGoal_Response",
         lambda m: (bool(m.accepted), m.stamp.sec, m.stamp.nanosec) == (True, 5, 6)),
        (na.GetResultResponseWire(GUID, SEQ, na.STATUS_SUCCEEDED), f"{PKG}GetResult_Response",
         lambda m: m.status == 4),
        (na.GetResultRequestWire(GUID, SEQ, na.UUID(UID)), f"{PKG}GetResult_Request",
         lambda m: bytes(m.goal_id.uuid) == UID),
        (na.CancelGoalRequestWire(GUID, SEQ, na.GoalInfo(na.UUID(UID), Time(1, 2))),
         "action_msgs/msg/CancelGoal_Request", lambda m: m.goal_info.stamp.nanosec == 2),
        (na.CancelGoalResponseWire(GUID, SEQ, na.CANCEL_ERROR_NONE, [na.GoalInfo(na.UUID(UID), Time(3, 4))] * 2),
         "action_msgs/msg/CancelGoal_Response",
         lambda m: m.return_code == 0 and len(m.goals_canceling) == 2 and m.goals_canceling[1].stamp.sec == 3),
    ]
    for ours, typename, check in cases:
        guid, seq, msg = from_service_bytes(STORE, typename, ours.serialize())
        assert (guid, seq) == (GUID, SEQ), typename
        assert check(msg), (typename, msg)
        assert type(ours).deserialize(to_service_bytes(STORE, typename, msg, GUID, SEQ)) == ours, typename


def test_feedback_and_status_topics_round_trip() -> None:
    fb = na.FeedbackMessage(na.UUID(UID))
    fb.feedback.distance_remaining, fb.feedback.number_of_recoveries = 2.5, 3
    fb.feedback.navigation_time.sec = 12
    fb.feedback.current_pose.header.frame_id = "map"
    m = STORE.deserialize_cdr(fb.serialize(), f"{PKG}FeedbackMessage")
    assert (m.feedback.distance_remaining, m.feedback.number_of_recoveries, m.feedback.navigation_time.sec) == (
        2.5, 3, 12)
    assert na.FeedbackMessage.deserialize(STORE.serialize_cdr(m, f"{PKG}FeedbackMessage")) == fb
    arr = na.GoalStatusArray([na.GoalStatus(na.GoalInfo(na.UUID(UID), Time(9, 0)), na.STATUS_EXECUTING)])
    s = STORE.deserialize_cdr(arr.serialize(), "action_msgs/msg/GoalStatusArray")
    assert [(bytes(g.goal_info.goal_id.uuid), g.status) for g in s.status_list] == [(UID, 2)]
