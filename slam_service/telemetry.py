"""What the SLAM service tells the outside about itself besides /map: lifecycle events and map spans.

``robonix/service/map/lifecycle`` (:class:`LifecycleAnnouncer`): a latched MapLifecycle message on every
change an agent cares about: INIT, ACTIVATE (``mode`` = the SLAM mode), DEACTIVATE (``mode`` =
``paused``), a loaded or reset map, and SHUTDOWN (``mode`` = ``shutdown``); ``generation`` counts the
announcements, so a late subscriber knows whether it missed one.

``slam.occupancy_grid`` spans (:class:`MapSpans`): with tracing on, each published map (at most once per
``period_s`` of wall time) becomes a span carrying the grid as an inline PNG and the robot's pose and
footprint, for a dashboard that only speaks OTLP. Built only when tracing is on.
"""

from __future__ import annotations

import base64
import logging
import threading
import time
from collections.abc import Callable, Sequence
from typing import Any

from robonix_api import telemetry
from robonix_api.dds import MapLifecycle
from robonix_common.grid import GridMap
from slam_service.render import render_map_png

log = logging.getLogger("slam_service.telemetry")

SPAN_NAME = "slam.occupancy_grid"
MAP_SPAN_PERIOD_S = 1.0
PAUSED, SHUTDOWN = "paused", "shutdown"


class LifecycleAnnouncer:
    """Publishes MapLifecycle on the lifecycle topic; thread-safe (lifecycle and RPC threads call it)."""

    def __init__(self, publisher: Any) -> None:
        self._pub = publisher
        self._lock = threading.Lock()
        self.generation = 0
        self.last: MapLifecycle | None = None

    def announce(self, map_id: str, mode: str) -> None:
        with self._lock:
            self.generation += 1
            msg = MapLifecycle(map_id=map_id, mode=mode, generation=self.generation)
            try:
                self._pub.publish(msg)
            except RuntimeError as exc:  # DDS closing under us at shutdown
                log.debug("map lifecycle not published: %s", exc)
                return
            self.last = msg
        log.info("map lifecycle: map %r, mode %s, generation %d", map_id, mode, msg.generation)


class MapSpans:
    """Turns published maps into rate-capped ``slam.occupancy_grid`` spans."""

    def __init__(self, tracer: Any, *, frame_id: str, base_frame: str, footprint: Sequence[tuple[float, float]],
                 robot_pose: Callable[[], tuple[float, float, float] | None], period_s: float = MAP_SPAN_PERIOD_S,
                 ) -> None:
        self._tracer = tracer
        self._frame_id, self._base_frame = frame_id, base_frame
        self._footprint = [float(v) for xy in footprint for v in xy]
        self._robot_pose = robot_pose
        self._period = period_s
        self._last = -float("inf")
        self.emitted = 0

    @classmethod
    def maybe(cls, **kwargs: Any) -> MapSpans | None:
        """``None`` when tracing is off, so nothing is rendered for nobody."""
        tracer = telemetry.tracer()
        return cls(tracer, **kwargs) if tracer is not None else None

    def on_map(self, grid: GridMap) -> None:
        """Called after each /map publication (publisher thread)."""
        now = time.monotonic()
        if now - self._last < self._period:
            return
        self._last = now
        png = render_map_png(grid)
        pose = self._robot_pose()
        with self._tracer.start_as_current_span(SPAN_NAME) as span:
            telemetry.set_attributes(span, (
                ("width", int(grid.width)), ("height", int(grid.height)), ("resolution", float(grid.resolution)),
                ("origin_x", float(grid.origin_x)), ("origin_y", float(grid.origin_y)),
                ("frame_id", self._frame_id), ("png_b64", base64.b64encode(png).decode("ascii")),
                ("base_frame", self._base_frame), ("footprint_polygon_xy", self._footprint),
                ("robot_x", pose[0] if pose else None), ("robot_y", pose[1] if pose else None),
                ("robot_yaw", pose[2] if pose else None)))
        self.emitted += 1
