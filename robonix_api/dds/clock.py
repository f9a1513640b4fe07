"""Sim time: a ``now()`` that follows /clock when ``use_sim_time`` is set, else the wall clock.

/clock is subscribed with rclcpp's ClockQoS (best effort, volatile, keep-last 1: the sensor_data
profile with depth 1), which matches both best-effort and reliable /clock publishers. Like ROS, sim time
reads 0.0 until the first tick. ``ClockPublisher`` (for the simulator) publishes best effort, depth 1,
so a stalled subscriber can never block the sim step.
"""

from __future__ import annotations

import threading
import time

from robonix_api.dds.messages import Clock, Time


class SimClock:
    """The time a provider runs on: the latest /clock with ``use_sim_time``, else the wall clock."""
    def __init__(self, node: object | None, use_sim_time: bool) -> None:
        self.use_sim_time = bool(use_sim_time)
        self._t = 0.0
        self._ticked = False
        self._cv = threading.Condition()
        self._sub = None
        if self.use_sim_time and node is not None:
            self._sub = node.create_subscription("/clock", Clock, self._on_clock, "clock")

    def _on_clock(self, msg: Clock) -> None:
        self.set_time(msg.clock.to_sec())

    def set_time(self, t: float) -> None:
        """Feed sim time directly (in-process pipelines, tests)."""
        with self._cv:
            self._t = float(t)
            self._ticked = True
            self._cv.notify_all()

    def now(self) -> float:
        """Seconds: latest /clock value with sim time, else ``time.time()``."""
        if not self.use_sim_time:
            return time.time()
        with self._cv:
            return self._t

    def now_msg(self) -> Time:
        """``now()`` as a ROS ``builtin_interfaces/Time`` for message headers."""
        return Time.from_sec(self.now())

    @property
    def ticked(self) -> bool:
        """Whether time is known: a /clock arrived (always true on wall time)."""
        return self._ticked or not self.use_sim_time

    def wait_for_first_tick(self, timeout: float | None = None) -> bool:
        """True once /clock has delivered (immediately without sim time); wall-clock timeout."""
        if not self.use_sim_time:
            return True
        with self._cv:
            return self._cv.wait_for(lambda: self._ticked, timeout)

    def sleep_until(self, t: float, timeout: float | None = None) -> bool:
        """Block until ``now() >= t``; False if the wall-clock ``timeout`` ran out first."""
        if not self.use_sim_time:
            dt = t - time.time()
            if timeout is not None and dt > timeout:
                time.sleep(max(0.0, timeout))
                return False
            time.sleep(max(0.0, dt))
            return True
        with self._cv:
            return self._cv.wait_for(lambda: self._t >= t, timeout)

    def sleep(self, dt: float, timeout: float | None = None) -> bool:
        """Sleep ``dt`` seconds of this clock's time; False when ``timeout`` (wall s) ran out first."""
        return self.sleep_until(self.now() + dt, timeout)

    def close(self) -> None:
        """Stop listening to /clock."""
        if self._sub is not None:
            self._sub.close()
            self._sub = None


class ClockPublisher:
    """Publishes /clock (the simulator's side)."""

    def __init__(self, node: object) -> None:
        self._pub = node.create_publisher("/clock", Clock, "clock")

    def publish(self, t: float) -> None:
        """Publish simulated time ``t`` (seconds) on /clock."""
        self._pub.publish(Clock(clock=Time.from_sec(t)))

    def close(self) -> None:
        """Stop publishing /clock."""
        self._pub.close()
