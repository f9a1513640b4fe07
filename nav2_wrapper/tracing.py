"""One OpenTelemetry span per accepted Navigate goal, from acceptance to its terminal state.

The span is a child of the caller's trace when the Navigate request carried W3C trace context (gRPC
metadata; over MCP the SDK has already made the ``_meta`` context current), so an agent sees its goal
as part of its own trace. It records the goal, the straight-line distance at the
start, the distance actually driven, recoveries, the final distance to the goal and the end state
(FAILED sets the span status to error with the reason). Only built when tracing is on
(``robonix_api.telemetry``); the loop calls :meth:`GoalSpans.sweep` each tick to close finished runs.
"""

from __future__ import annotations

import math
from typing import Any

from nav2_wrapper.core import GoalRecord
from nav2_wrapper.core.navigator import FAILED, TERMINAL
from robonix_api import telemetry
from robonix_common.geometry import Pose2D

SPAN_NAME = "nav.navigate"


class _Open:
    __slots__ = ("span", "rec", "last", "driven")

    def __init__(self, span: Any, rec: GoalRecord, pose: Pose2D | None) -> None:
        self.span, self.rec, self.last, self.driven = span, rec, pose, 0.0


class GoalSpans:
    """The open goal spans of one navigation session (call under the loop's lock)."""

    def __init__(self, tracer: Any, frame: str) -> None:
        self._tracer, self._frame = tracer, frame
        self._open: dict[str, _Open] = {}

    @classmethod
    def maybe(cls, frame: str) -> GoalSpans | None:
        """``None`` when tracing is off, so the loop does no span work at all."""
        tracer = telemetry.tracer()
        return cls(tracer, frame) if tracer is not None else None

    def start(self, rec: GoalRecord, parent: Any, pose: Pose2D | None) -> None:
        x, y, yaw = rec.goal
        span = self._tracer.start_span(SPAN_NAME, context=parent)
        telemetry.set_attributes(span, (
            ("nav.run_id", rec.run_id), ("nav.frame", self._frame), ("nav.goal.x", x), ("nav.goal.y", y),
            ("nav.goal.yaw", yaw), ("nav.start_state", rec.state),
            ("nav.start.x", pose[0] if pose else None), ("nav.start.y", pose[1] if pose else None),
            ("nav.goal_distance_m", math.hypot(x - pose[0], y - pose[1]) if pose else None)))
        self._open[rec.run_id] = _Open(span, rec, pose)

    def sweep(self, pose: Pose2D | None) -> None:
        """Add the distance driven since the last tick; end the spans of runs that reached a terminal state."""
        for rid, o in list(self._open.items()):
            if pose is not None and o.last is not None:
                o.driven += math.hypot(pose[0] - o.last[0], pose[1] - o.last[1])
            if pose is not None:
                o.last = pose
            if o.rec.state in TERMINAL:
                self._end(rid, o)

    def end_all(self) -> None:
        """Session over: close every span still open with the record's state as it stands."""
        for rid, o in list(self._open.items()):
            self._end(rid, o)

    def _end(self, rid: str, o: _Open) -> None:
        from opentelemetry.trace import Status, StatusCode

        rec, span = o.rec, o.span
        x, y, _ = rec.goal
        telemetry.set_attributes(span, (
            ("nav.end_state", rec.state), ("nav.detail", rec.detail), ("nav.recoveries", int(rec.recoveries)),
            ("nav.distance_driven_m", round(o.driven, 3)),
            ("nav.final_error_m", round(math.hypot(x - o.last[0], y - o.last[1]), 3) if o.last else None),
            ("nav.duration_s", (rec.finished - rec.started) if rec.finished is not None else None)))
        if rec.state == FAILED:
            span.set_status(Status(StatusCode.ERROR, rec.detail))
        span.end()
        del self._open[rid]
