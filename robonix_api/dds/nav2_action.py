"""nav2_msgs/action/NavigateToPose over DDS, as rcl_action + rmw_cyclonedds put it on the wire (ROS 2 Humble).

An action ``/navigate_to_pose`` is three services and two topics (rcl_action's naming):

- ``rq/navigate_to_pose/_action/send_goalRequest`` / ``rr/…/send_goalReply`` (NavigateToPose_SendGoal)
- ``rq/navigate_to_pose/_action/get_resultRequest`` / ``rr/…/get_resultReply`` (NavigateToPose_GetResult)
- ``rq/navigate_to_pose/_action/cancel_goalRequest`` / ``rr/…/cancel_goalReply`` (action_msgs/srv/CancelGoal)
- ``rt/navigate_to_pose/_action/feedback`` (NavigateToPose_FeedbackMessage), reliable volatile
- ``rt/navigate_to_pose/_action/status`` (action_msgs/msg/GoalStatusArray), reliable transient_local depth 1

rmw_cyclonedds writes every service sample as a 16-byte request header (``uint64 guid`` of the client,
``int64 sequence number``) followed by the request or response fields; a reply echoes the request's header so
the client can match it. The ``*Wire`` structs below are exactly that (header first, then the ROS fields:
the header is 8-aligned, so the fields' CDR alignment is as in the bare message). Types follow navigation2's
Humble ``NavigateToPose.action`` (result ``std_msgs/Empty``), kept beside this file as ``NavigateToPose.action``.
"""

# no `from __future__ import annotations`: cyclonedds resolves the IDL field annotations at runtime
from dataclasses import dataclass, field
from pathlib import Path

from cyclonedds.idl import IdlStruct
from cyclonedds.idl.annotations import final
from cyclonedds.idl.types import array, float32, int8, int16, int64, sequence, uint8, uint64

from robonix_api.dds.messages import Duration, PoseStamped, Time

ACTION_FILE = Path(__file__).with_name("NavigateToPose.action")

# action_msgs/msg/GoalStatus
STATUS_UNKNOWN, STATUS_ACCEPTED, STATUS_EXECUTING, STATUS_CANCELING = 0, 1, 2, 3
STATUS_SUCCEEDED, STATUS_CANCELED, STATUS_ABORTED = 4, 5, 6
# action_msgs/srv/CancelGoal return codes
CANCEL_ERROR_NONE, CANCEL_ERROR_REJECTED, CANCEL_ERROR_UNKNOWN_GOAL_ID, CANCEL_ERROR_GOAL_TERMINATED = 0, 1, 2, 3


def action_topics(action: str) -> dict[str, str]:
    """DDS topic names of ``action`` (``/navigate_to_pose``) by role."""
    a = action.strip().strip("/")
    return {"send_goal_rq": f"rq/{a}/_action/send_goalRequest", "send_goal_rr": f"rr/{a}/_action/send_goalReply",
            "get_result_rq": f"rq/{a}/_action/get_resultRequest",
            "get_result_rr": f"rr/{a}/_action/get_resultReply",
            "cancel_rq": f"rq/{a}/_action/cancel_goalRequest", "cancel_rr": f"rr/{a}/_action/cancel_goalReply",
            "feedback": f"/{a}/_action/feedback", "status": f"/{a}/_action/status"}


@final
@dataclass
class UUID(IdlStruct, typename="unique_identifier_msgs::msg::dds_::UUID_"):
    """unique_identifier_msgs/UUID: a goal id."""
    uuid: array[uint8, 16] = field(default_factory=lambda: [0] * 16)


@final
@dataclass
class Empty(IdlStruct, typename="std_msgs::msg::dds_::Empty_"):
    """std_msgs/Empty: IDL needs one member (rosidl adds this one)."""
    structure_needs_at_least_one_member: uint8 = 0


@final
@dataclass
class GoalInfo(IdlStruct, typename="action_msgs::msg::dds_::GoalInfo_"):
    """action_msgs/GoalInfo: a goal's id and when it was accepted."""
    goal_id: UUID = field(default_factory=UUID)
    stamp: Time = field(default_factory=Time)


@final
@dataclass
class GoalStatus(IdlStruct, typename="action_msgs::msg::dds_::GoalStatus_"):
    """action_msgs/GoalStatus."""
    goal_info: GoalInfo = field(default_factory=GoalInfo)
    status: int8 = STATUS_UNKNOWN


@final
@dataclass
class GoalStatusArray(IdlStruct, typename="action_msgs::msg::dds_::GoalStatusArray_"):
    """action_msgs/GoalStatusArray: the status topic's message."""
    status_list: sequence[GoalStatus] = field(default_factory=list)


@final
@dataclass
class NavigateToPoseGoal(IdlStruct, typename="nav2_msgs::action::dds_::NavigateToPose_Goal_"):
    """NavigateToPose goal: where to go (behavior_tree is accepted and ignored: no BT here)."""
    pose: PoseStamped = field(default_factory=PoseStamped)
    behavior_tree: str = ""


@final
@dataclass
class NavigateToPoseResult(IdlStruct, typename="nav2_msgs::action::dds_::NavigateToPose_Result_"):
    """NavigateToPose result (Humble: std_msgs/Empty; the outcome is the goal status)."""
    result: Empty = field(default_factory=Empty)


@final
@dataclass
class NavigateToPoseFeedback(IdlStruct, typename="nav2_msgs::action::dds_::NavigateToPose_Feedback_"):
    """NavigateToPose feedback."""
    current_pose: PoseStamped = field(default_factory=PoseStamped)
    navigation_time: Duration = field(default_factory=Duration)
    estimated_time_remaining: Duration = field(default_factory=Duration)
    number_of_recoveries: int16 = 0
    distance_remaining: float32 = 0.0


@final
@dataclass
class FeedbackMessage(IdlStruct, typename="nav2_msgs::action::dds_::NavigateToPose_FeedbackMessage_"):
    """The feedback topic's message: which goal, and its feedback."""
    goal_id: UUID = field(default_factory=UUID)
    feedback: NavigateToPoseFeedback = field(default_factory=NavigateToPoseFeedback)


# --- service samples: rmw_cyclonedds request header + the ROS request/response fields ------------
@final
@dataclass
class SendGoalRequestWire(IdlStruct, typename="nav2_msgs::action::dds_::NavigateToPose_SendGoal_Request_"):
    """NavigateToPose_SendGoal_Request on the wire."""
    client_guid: uint64 = 0
    sequence_number: int64 = 0
    goal_id: UUID = field(default_factory=UUID)
    goal: NavigateToPoseGoal = field(default_factory=NavigateToPoseGoal)


@final
@dataclass
class SendGoalResponseWire(IdlStruct, typename="nav2_msgs::action::dds_::NavigateToPose_SendGoal_Response_"):
    """NavigateToPose_SendGoal_Response on the wire."""
    client_guid: uint64 = 0
    sequence_number: int64 = 0
    accepted: bool = False
    stamp: Time = field(default_factory=Time)


@final
@dataclass
class GetResultRequestWire(IdlStruct, typename="nav2_msgs::action::dds_::NavigateToPose_GetResult_Request_"):
    """NavigateToPose_GetResult_Request on the wire."""
    client_guid: uint64 = 0
    sequence_number: int64 = 0
    goal_id: UUID = field(default_factory=UUID)


@final
@dataclass
class GetResultResponseWire(IdlStruct, typename="nav2_msgs::action::dds_::NavigateToPose_GetResult_Response_"):
    """NavigateToPose_GetResult_Response on the wire."""
    client_guid: uint64 = 0
    sequence_number: int64 = 0
    status: int8 = STATUS_UNKNOWN
    result: NavigateToPoseResult = field(default_factory=NavigateToPoseResult)


@final
@dataclass
class CancelGoalRequestWire(IdlStruct, typename="action_msgs::srv::dds_::CancelGoal_Request_"):
    """action_msgs/srv/CancelGoal_Request on the wire (zero id and stamp: cancel all goals)."""
    client_guid: uint64 = 0
    sequence_number: int64 = 0
    goal_info: GoalInfo = field(default_factory=GoalInfo)


@final
@dataclass
class CancelGoalResponseWire(IdlStruct, typename="action_msgs::srv::dds_::CancelGoal_Response_"):
    """action_msgs/srv/CancelGoal_Response on the wire."""
    client_guid: uint64 = 0
    sequence_number: int64 = 0
    return_code: int8 = CANCEL_ERROR_NONE
    goals_canceling: sequence[GoalInfo] = field(default_factory=list)


#: role -> (type, QoS preset): service samples are reliable volatile (rmw_qos_profile_services_default)
SERVICE_TYPES = {
    "send_goal_rq": SendGoalRequestWire, "send_goal_rr": SendGoalResponseWire,
    "get_result_rq": GetResultRequestWire, "get_result_rr": GetResultResponseWire,
    "cancel_rq": CancelGoalRequestWire, "cancel_rr": CancelGoalResponseWire,
}
