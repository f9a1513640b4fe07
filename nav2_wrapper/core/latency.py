"""Control latency: how long after the pose it was computed for a velocity command takes effect, and where
the base will be by then.

In one process (the in-process benchmarks) the simulator waits for the controller, so a command acts on
the pose it was computed for. In the multi-process system it does not: the odometry behind the pose is
already some sim time old when a tick reads it, the tick itself takes wall time that the simulator turns
into ``real_time_factor`` times as much sim time (MPPI's ~7 ms median, tens of ms on a loaded machine,
become 20–100+ ms at rtf 3), and all the while the base keeps moving with the previous command. A
controller that checks its candidates from the stale pose checks them from a place the base has already
left: at 0.5 m/s, 100 ms is 5 cm — about the clearance the footprint check keeps in a doorway.

So the loop measures the latency (pose age + the sim time its recent ticks took) and the controller
plans from the pose predicted over it with the measured body twist. Nothing here depends on wall-clock
speed: the inputs are sim-time figures the loop measured.
"""

from __future__ import annotations

import math
from collections import deque

from robonix_common.geometry import Pose2D, wrap_angle


def predict_pose(pose: Pose2D, vel: tuple[float, float, float], dt: float) -> Pose2D:
    """The pose after holding the body twist ``vel`` (vx, vy, wz) for ``dt`` seconds (exact circular arc)."""
    if dt <= 0.0:
        return pose
    vx, vy, wz = vel
    th = pose[2]
    a = wz * dt
    if abs(a) < 1e-6:
        bx, by = vx * dt, vy * dt
    else:
        s, c1 = math.sin(a), 1.0 - math.cos(a)
        bx, by = (vx * s - vy * c1) / wz, (vx * c1 + vy * s) / wz
    c, s = math.cos(th), math.sin(th)
    return pose[0] + c * bx - s * by, pose[1] + s * bx + c * by, float(wrap_angle(th + a))


def mean_twist(vel: tuple[float, float, float], cmd: tuple[float, float, float],
               acc: tuple[float, float, float], dt: float) -> tuple[float, float, float]:
    """The mean body twist over ``dt`` of a base at ``vel`` that follows the command ``cmd`` at the
    acceleration limits ``acc`` (each axis ramps linearly to its target, then holds it).

    During the latency the base is still executing the commands already sent, not holding its measured
    twist: at 0.2 s and 1.5 m/s^2 the two differ by up to 3 cm of travel, and a turn started or stopped
    by the last command by up to 0.06 rad."""
    if dt <= 0.0:
        return vel
    out = []
    for v0, u, a in zip(vel, cmd, acc, strict=True):
        ramp = abs(u - v0) / a if a > 0 else math.inf
        if ramp >= dt:      # still accelerating at the end: the mean is the mid-point speed
            out.append(v0 + math.copysign(a * dt / 2.0, u - v0))
        else:               # ramp, then hold u
            out.append(((v0 + u) / 2.0 * ramp + u * (dt - ramp)) / dt)
    return out[0], out[1], out[2]


class LatencyEstimate:
    """Rolling estimate of the sim time a control tick takes, for predicting where its command acts.

    ``expected(pose_age)`` = the age of the pose being used + a high quantile of the recent ticks' durations
    (a tick's own duration is known only after it, and the next one is usually alike; a high quantile
    rather than the mean because under-predicting is what lets the body reach an obstacle)."""

    def __init__(self, window: int = 40, quantile: float = 0.9) -> None:
        self._ticks: deque[float] = deque(maxlen=window)
        self.quantile = quantile

    def add_tick(self, duration: float) -> None:
        """One tick's duration (sim s from reading the pose to publishing the command)."""
        if math.isfinite(duration) and duration >= 0.0:
            self._ticks.append(duration)

    def tick_quantile(self) -> float:
        if not self._ticks:
            return 0.0
        xs = sorted(self._ticks)
        return xs[min(len(xs) - 1, int(self.quantile * len(xs)))]

    def expected(self, pose_age: float) -> float:
        """Sim seconds from the pose's stamp until a command computed now takes effect."""
        age = pose_age if math.isfinite(pose_age) and pose_age > 0.0 else 0.0
        return age + self.tick_quantile()
