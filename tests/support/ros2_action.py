"""An independent NavigateToPose action client for tests: payloads serialized and decoded by rosbags from
navigation2's Humble ``.action`` text (the services derived as rosidl derives them), the 16-byte rmw_cyclonedds
request header packed by hand, raw bytes written and taken with cyclonedds' C-layer calls. Our own IDL structs
are used only to register the DDS topics' type names."""

from __future__ import annotations

import itertools
import os
import struct
import time
from typing import Any

from robonix_api.dds import nav2_action as na

PKG = "nav2_msgs/msg/NavigateToPose_"  # rosbags needs msg namespaces; names do not reach the bytes
HEADER = struct.Struct("<Qq")  # rmw_cyclonedds cdds_request_header_t: client guid, sequence number
ENCAPSULATION = b"\x00\x01\x00\x00"  # CDR little endian


def action_store() -> Any:
    """rosbags Humble typestore plus the action's derived types, built from the .action text."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    goal, result, feedback = na.ACTION_FILE.read_text().split("---")
    derived = {
        f"{PKG}Goal": goal, f"{PKG}Result": result, f"{PKG}Feedback": feedback,
        f"{PKG}SendGoal_Request": f"unique_identifier_msgs/UUID goal_id\n{PKG}Goal goal",
        f"{PKG}SendGoal_Response": "bool accepted\nbuiltin_interfaces/Time stamp",
        f"{PKG}GetResult_Request": "unique_identifier_msgs/UUID goal_id",
        f"{PKG}GetResult_Response": f"int8 status\n{PKG}Result result",
        f"{PKG}FeedbackMessage": f"unique_identifier_msgs/UUID goal_id\n{PKG}Feedback feedback",
        "action_msgs/msg/CancelGoal_Request": "action_msgs/GoalInfo goal_info",
        "action_msgs/msg/CancelGoal_Response": "int8 return_code\naction_msgs/GoalInfo[] goals_canceling",
    }
    store = get_typestore(Stores.ROS2_HUMBLE)
    types: dict[str, Any] = {}
    for name, text in derived.items():
        types.update(get_types_from_msg(text, name))
    store.register(types)
    return store


def to_service_bytes(store: Any, typename: str, msg: Any, guid: int, seq: int) -> bytes:
    """A request/reply sample as rmw_cyclonedds writes it: encapsulation, header, then the fields."""
    body = store.serialize_cdr(msg, typename)
    assert body[:4] == ENCAPSULATION
    return ENCAPSULATION + HEADER.pack(guid, seq) + body[4:]


def from_service_bytes(store: Any, typename: str, data: bytes) -> tuple[int, int, Any]:
    """(guid, seq, message) of a request/reply sample."""
    guid, seq = HEADER.unpack_from(data, 4)
    return guid, seq, store.deserialize_cdr(ENCAPSULATION + data[4 + HEADER.size:], typename)


class ActionClient:
    """send_goal / get_result / cancel_goal over raw DDS, and the feedback and status topics, for one action."""

    def __init__(self, participant: Any, action: str = "/navigate_to_pose") -> None:
        from cyclonedds.pub import DataWriter
        from cyclonedds.sub import DataReader
        from cyclonedds.topic import Topic

        from robonix_api.dds.qos import resolve_qos, writer_qos

        self.store = action_store()
        self.guid = int.from_bytes(os.urandom(8), "little")
        self._seq = itertools.count(1)
        names = na.action_topics(action)
        qos = resolve_qos("reliable", 10)
        self.ents: dict[str, Any] = {}
        for role, typ in na.SERVICE_TYPES.items():
            t = Topic(participant, names[role], typ)
            self.ents[role] = DataWriter(participant, t, writer_qos(qos)) if role.endswith("_rq") else \
                DataReader(participant, t, qos)
        self.ents["feedback"] = DataReader(participant, Topic(participant, "rt" + names["feedback"],
                                                              na.FeedbackMessage), qos)
        self.ents["status"] = DataReader(participant, Topic(participant, "rt" + names["status"], na.GoalStatusArray),
                                         resolve_qos("latched", 1))
        self.replies: dict[tuple[str, int], Any] = {}
        self.feedback: list[Any] = []
        self.status: list[Any] = []

    def _raw_take(self, role: str) -> list[bytes]:
        from cyclonedds._clayer import ddspy_take
        from cyclonedds.core import InstanceState, SampleState, ViewState

        got = ddspy_take(self.ents[role]._ref, SampleState.Any | ViewState.Any | InstanceState.Any, 64)
        return [] if isinstance(got, int) else [d for d, info in got if info.valid_data]

    def _request(self, role: str, typename: str, msg: Any) -> int:
        from cyclonedds._clayer import ddspy_write

        seq = next(self._seq)
        ret = ddspy_write(self.ents[role]._ref, to_service_bytes(self.store, typename, msg, self.guid, seq))
        assert ret == 0, ret
        return seq

    def poll(self) -> None:
        for role, typename in (("send_goal_rr", f"{PKG}SendGoal_Response"),
                               ("get_result_rr", f"{PKG}GetResult_Response"),
                               ("cancel_rr", "action_msgs/msg/CancelGoal_Response")):
            for data in self._raw_take(role):
                guid, seq, msg = from_service_bytes(self.store, typename, data)
                if guid == self.guid:
                    self.replies[(role, seq)] = msg
        des = self.store.deserialize_cdr
        self.feedback += [des(d, f"{PKG}FeedbackMessage") for d in self._raw_take("feedback")]
        self.status += [des(d, "action_msgs/msg/GoalStatusArray") for d in self._raw_take("status")]

    def wait_reply(self, role: str, seq: int, timeout_s: float) -> Any:
        end = time.monotonic() + timeout_s
        while (role, seq) not in self.replies:
            assert time.monotonic() < end, f"no {role} reply to request {seq} in {timeout_s} s"
            time.sleep(0.05)
            self.poll()
        return self.replies.pop((role, seq))

    def uuid(self) -> Any:
        """A random goal id (rosbags UUID)."""
        import numpy as np

        return self.store.types["unique_identifier_msgs/msg/UUID"](uuid=np.frombuffer(os.urandom(16), np.uint8))

    def send_goal(self, goal_id: Any, x: float, y: float, frame: str = "map") -> int:
        t = self.store.types
        Time = t["builtin_interfaces/msg/Time"]
        header = t["std_msgs/msg/Header"](stamp=Time(sec=0, nanosec=0), frame_id=frame)
        pose = t["geometry_msgs/msg/Pose"](position=t["geometry_msgs/msg/Point"](x=x, y=y, z=0.0),
                                           orientation=t["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0))
        goal = t[f"{PKG}Goal"](pose=t["geometry_msgs/msg/PoseStamped"](header=header, pose=pose), behavior_tree="")
        return self._request("send_goal_rq", f"{PKG}SendGoal_Request", t[f"{PKG}SendGoal_Request"](goal_id, goal))

    def get_result(self, goal_id: Any) -> int:
        return self._request("get_result_rq", f"{PKG}GetResult_Request",
                             self.store.types[f"{PKG}GetResult_Request"](goal_id))

    def cancel(self, goal_id: Any) -> int:
        t = self.store.types
        zero = t["builtin_interfaces/msg/Time"](sec=0, nanosec=0)
        info = t["action_msgs/msg/GoalInfo"](goal_id=goal_id, stamp=zero)
        name = "action_msgs/msg/CancelGoal_Request"
        return self._request("cancel_rq", name, t[name](info))

    def close(self) -> None:
        for e in self.ents.values():
            e.__del__()
        self.ents.clear()
