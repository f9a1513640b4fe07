"""The ROS 2 ``navigate_to_pose`` action server and the ``/goal_pose`` subscription, over DDS.

What ``ros2 action send_goal``, Nav2's simple commander and RViz2's "2D Goal Pose" talk to, mapped onto the
same goal machinery as the gRPC/MCP ``navigate`` contract: a goal becomes ``NavLoop.navigate`` (one run_id
space: the run_id is logged and shown by ``rbnx nav-status``), cancel becomes ``NavLoop.cancel``, and the
goal's state maps onto action_msgs/GoalStatus (PENDING -> ACCEPTED, RUNNING -> EXECUTING, SUCCEEDED,
CANCELED, FAILED -> ABORTED). A new goal preempts the running one, as Nav2's bt_navigator does; the preempted
goal ends CANCELED or ABORTED as its run record says. Wire details are in
:mod:`robonix_api.dds.nav2_action`. One thread serves the requests and publishes feedback (5 Hz) and status
(on change); get_result replies wait until the goal is terminal.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from nav2_wrapper.core.navigator import CANCELED, FAILED, PENDING, RUNNING, SUCCEEDED
from robonix_api.dds import nav2_action as na
from robonix_api.dds.messages import Duration, PoseStamped, Time

from .goals import parse_goal

log = logging.getLogger("nav2_wrapper.ros_action")

ACTION = "/navigate_to_pose"
GOAL_POSE = "/goal_pose"
TICK_S = 0.05
FEEDBACK_S = 0.2
KEEP_GOALS = 32  # goals remembered for status / get_result (oldest terminal ones dropped)
_STATUS = {PENDING: na.STATUS_ACCEPTED, RUNNING: na.STATUS_EXECUTING, SUCCEEDED: na.STATUS_SUCCEEDED,
           CANCELED: na.STATUS_CANCELED, FAILED: na.STATUS_ABORTED}


@dataclass
class _Goal:
    uuid: bytes
    run_id: str
    accepted_at: Time
    status: int = na.STATUS_ACCEPTED
    waiting: list[tuple[int, int]] = field(default_factory=list)  # get_result headers to answer when terminal


def _time_msg(t: float) -> Time:
    return Time.from_sec(t)


def _duration(s: float) -> Duration:
    s = max(0.0, s) if math.isfinite(s) else 0.0
    return Duration(sec=int(s), nanosec=int((s - int(s)) * 1e9))


class NavigateToPoseServer:
    """The action server on ``node`` (a DdsNode); ``loop()`` is the current NavLoop (None before INIT)."""

    def __init__(self, node: Any, loop: Callable[[], Any], action: str = ACTION, goal_topic: str = GOAL_POSE) -> None:
        from cyclonedds.pub import DataWriter
        from cyclonedds.sub import DataReader
        from cyclonedds.topic import Topic

        from robonix_api.dds.qos import resolve_qos, writer_qos

        self.node, self._loop = node, loop
        self.action = action
        names = na.action_topics(action)
        qos = resolve_qos("reliable", 10)
        self._ents: dict[str, Any] = {}
        for role, typ in na.SERVICE_TYPES.items():
            topic = Topic(node.participant, names[role], typ)
            self._ents[role] = (DataReader(node.participant, topic, qos) if role.endswith("_rq")
                                else DataWriter(node.participant, topic, writer_qos(qos)))
        node.announce(*self._ents.values())
        self._feedback = node.create_publisher(names["feedback"], na.FeedbackMessage, "reliable", 10)
        self._status = node.create_publisher(names["status"], na.GoalStatusArray, "latched", 1)
        self._goal_sub = node.create_subscription(goal_topic, PoseStamped, self._on_goal_pose, "best_effort", 10)
        self._goals: OrderedDict[bytes, _Goal] = OrderedDict()
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._last_status: list[tuple[bytes, int]] = []
        self._next_feedback = 0.0
        self._thread = threading.Thread(target=self._run, name="nav-action", daemon=True)
        self._thread.start()
        log.info("ROS 2 action %s and %s served over DDS", action, goal_topic)

    # ---- requests --------------------------------------------------------------------------------
    def _reply(self, role: str, msg: Any) -> None:
        self._ents[role].write(msg)

    def _send_goal(self, req: na.SendGoalRequestWire) -> None:
        uid = bytes(req.goal_id.uuid)
        loop = self._loop()
        reason = ""
        rec = None
        if loop is None:
            reason = "navigation not initialized"
        else:
            goal = parse_goal(req.goal.pose)
            rec, _preempted = loop.navigate(goal)
            if rec is None:
                reason = "navigation is not active"
            elif not rec.accepted:
                reason = rec.detail
        now = _time_msg(time.time())
        if rec is None or not rec.accepted:
            log.info("%s goal %s rejected: %s", self.action, uid.hex(), reason)
            self._reply("send_goal_rr", na.SendGoalResponseWire(req.client_guid, req.sequence_number, False, now))
            return
        with self._lock:
            self._goals[uid] = _Goal(uid, rec.run_id, now)
            self._trim()
        log.info("%s goal %s accepted as run %s", self.action, uid.hex(), rec.run_id)
        self._reply("send_goal_rr", na.SendGoalResponseWire(req.client_guid, req.sequence_number, True, now))

    def _get_result(self, req: na.GetResultRequestWire) -> None:
        with self._lock:
            g = self._goals.get(bytes(req.goal_id.uuid))
            if g is not None and g.status not in (na.STATUS_SUCCEEDED, na.STATUS_CANCELED, na.STATUS_ABORTED):
                g.waiting.append((req.client_guid, req.sequence_number))
                return
        status = na.STATUS_UNKNOWN if g is None else g.status
        self._reply("get_result_rr", na.GetResultResponseWire(req.client_guid, req.sequence_number, status))

    def _cancel(self, req: na.CancelGoalRequestWire) -> None:
        uid = bytes(req.goal_info.goal_id.uuid)
        stamp = req.goal_info.stamp.to_sec()
        with self._lock:
            if uid == bytes(16):  # zero id: all goals (accepted at or before stamp, if one is given)
                targets = [g for g in self._goals.values() if stamp == 0 or g.accepted_at.to_sec() <= stamp]
            else:
                targets = [self._goals[uid]] if uid in self._goals else []
        loop = self._loop()
        canceling = []
        for g in targets:
            rec, was_live = loop.cancel(g.run_id) if loop is not None else (None, False)
            if was_live:
                canceling.append(na.GoalInfo(na.UUID(list(g.uuid)), g.accepted_at))
        if canceling:
            code = na.CANCEL_ERROR_NONE
        elif not targets and uid != bytes(16):
            code = na.CANCEL_ERROR_UNKNOWN_GOAL_ID
        elif targets:
            code = na.CANCEL_ERROR_GOAL_TERMINATED
        else:
            code = na.CANCEL_ERROR_REJECTED
        self._reply("cancel_rr", na.CancelGoalResponseWire(req.client_guid, req.sequence_number, code, canceling))

    def _on_goal_pose(self, msg: PoseStamped) -> None:
        """RViz2's "2D Goal Pose": a goal like any other (no action client to answer)."""
        loop = self._loop()
        if loop is None:
            log.warning("%s ignored: navigation not initialized", GOAL_POSE)
            return
        rec, _ = loop.navigate(parse_goal(msg))
        if rec is None:
            log.warning("%s ignored: navigation is not active", GOAL_POSE)
        else:
            log.info("%s: run %s %s", GOAL_POSE, rec.run_id, "accepted" if rec.accepted else f"rejected: {rec.detail}")

    # ---- the thread ------------------------------------------------------------------------------
    def _run(self) -> None:
        handlers = {"send_goal_rq": self._send_goal, "get_result_rq": self._get_result, "cancel_rq": self._cancel}
        while not self._stop.wait(TICK_S):
            try:
                for role, handle in handlers.items():
                    for req in self._ents[role].take(N=16):
                        if hasattr(req, "client_guid"):  # not an InvalidSample (a client's writer went away)
                            handle(req)
                self._update()
            except Exception:  # one bad request must not end the server
                if self._stop.is_set() or getattr(self.node, "_closed", False):
                    return  # shutting down: the node deleted our entities
                log.exception("%s: error serving a request", self.action)

    def _update(self) -> None:
        """Refresh goal states from the run records; answer waiting get_results; publish status and feedback."""
        loop = self._loop()
        answers: list[tuple[int, int, int]] = []
        with self._lock:
            for g in self._goals.values():
                rec = loop.status(g.run_id) if loop is not None else None
                if rec is not None:
                    g.status = _STATUS.get(rec.state, na.STATUS_UNKNOWN)
                elif g.status not in (na.STATUS_SUCCEEDED, na.STATUS_CANCELED, na.STATUS_ABORTED):
                    g.status = na.STATUS_ABORTED  # the session that ran it is gone
                if g.waiting and g.status in (na.STATUS_SUCCEEDED, na.STATUS_CANCELED, na.STATUS_ABORTED):
                    answers += [(guid, seq, g.status) for guid, seq in g.waiting]
                    g.waiting.clear()
            snapshot = [(g.uuid, g.status) for g in self._goals.values()]
            infos = {g.uuid: g.accepted_at for g in self._goals.values()}
            active = [g for g in self._goals.values() if g.status == na.STATUS_EXECUTING]
        for guid, seq, status in answers:
            self._reply("get_result_rr", na.GetResultResponseWire(guid, seq, status))
        if snapshot != self._last_status:
            self._last_status = snapshot
            self._status.publish(na.GoalStatusArray([na.GoalStatus(na.GoalInfo(na.UUID(list(u)), infos[u]), s)
                                                     for u, s in snapshot]))
        now = time.monotonic()
        if active and loop is not None and now >= self._next_feedback:
            self._next_feedback = now + FEEDBACK_S
            for g in active:
                self._publish_feedback(loop, g)

    def _publish_feedback(self, loop: Any, g: _Goal) -> None:
        rec = loop.status(g.run_id)
        if rec is None:
            return
        fb = na.NavigateToPoseFeedback(number_of_recoveries=int(rec.recoveries))
        left = loop.remaining(rec)
        fb.distance_remaining = float(left) if left is not None else 0.0
        clock_now = loop.inputs.clock.now()
        fb.navigation_time = _duration(clock_now - rec.started)
        vmax = float(loop.speed.mps(loop.speed.effective()[0]))  # the speed limit in force
        if left is not None and vmax > 0:
            fb.estimated_time_remaining = _duration(left / vmax)
        try:
            x, y, yaw = loop.inputs.robot_state(clock_now).pose
            fb.current_pose.header.frame_id = loop.cfg.frames.map
            fb.current_pose.header.stamp = Time.from_sec(clock_now)
            fb.current_pose.pose.position.x, fb.current_pose.pose.position.y = float(x), float(y)
            q = fb.current_pose.pose.orientation
            q.z, q.w = math.sin(yaw / 2), math.cos(yaw / 2)
        except Exception:  # no pose yet (TF not ready): the feedback still carries the distance
            log.debug("feedback without current_pose", exc_info=True)
        self._feedback.publish(na.FeedbackMessage(na.UUID(list(g.uuid)), fb))

    def _trim(self) -> None:
        while len(self._goals) > KEEP_GOALS:
            oldest = next((u for u, g in self._goals.items() if g.status in (
                na.STATUS_SUCCEEDED, na.STATUS_CANCELED, na.STATUS_ABORTED) and not g.waiting), None)
            if oldest is None:
                return
            del self._goals[oldest]

    def close(self) -> None:
        """Stop the thread and delete the entities. Idempotent."""
        if self._stop.is_set():
            return
        self._stop.set()
        self._thread.join(5.0)
        self.node.unannounce(*self._ents.values())
        for ent in self._ents.values():
            ent.__del__()
        self._ents.clear()
        for e in (self._feedback, self._status, self._goal_sub):
            e.close()
