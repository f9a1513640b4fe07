"""Wheel-like odometry with drift, integrated at a fixed rate from the base's measured motion.

Each tick takes the true motion since the previous tick in the previous body frame (what encoders
measure), corrupts its average velocities v = (vx, vy) and w with

    v_meas = v * (1 + scale_bias + N(0, v_scale_std)) + N(0, v_add_std)          (per tick)
    w_meas = w * (1 + N(0, w_scale_std)) + w_bias + N(0, w_add_std)

and composes the corrupted increment onto the odometry pose. Additive terms apply only while the base
moves (encoders do not tick at rest). With all parameters zero the chain of relative/compose is exact,
so odometry equals ground truth to floating-point precision at any tick rate.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from robonix_common.geometry import Pose2D

from .spec import check_ranges, param

MOVING_EPS = 1e-4  # m/s or rad/s: below this the base counts as at rest


def _wrap(a: float) -> float:
    return (a + math.pi) % (2.0 * math.pi) - math.pi


# Scalar SE(2) ops: the same conventions as robonix_common.geometry.compose/relative, without numpy's
# per-call overhead (these run at the odometry rate inside the stepping loop).
def compose(a: Pose2D, b: Pose2D) -> Pose2D:
    c, s = math.cos(a[2]), math.sin(a[2])
    return (a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], _wrap(a[2] + b[2]))


def relative(a: Pose2D, b: Pose2D) -> Pose2D:
    """Pose b expressed in frame a."""
    c, s = math.cos(a[2]), math.sin(a[2])
    dx, dy = b[0] - a[0], b[1] - a[1]
    return (c * dx + s * dy, -s * dx + c * dy, _wrap(b[2] - a[2]))


@dataclass(frozen=True)
class OdomNoise:
    """The simulated wheel odometry's error model (the formulas are in this module's docstring)."""

    v_scale_std: float = param(0.0, ge=0, doc="std dev of the linear speed scale error per tick (fraction)")
    w_scale_std: float = param(0.0, ge=0, doc="std dev of the yaw rate scale error per tick (fraction)")
    v_add_std: float = param(0.0, ge=0, doc="std dev of additive linear speed noise per tick while moving (m/s)")
    w_add_std: float = param(0.0, ge=0, doc="std dev of additive yaw rate noise per tick while moving (rad/s)")
    scale_bias: float = param(0.0, doc="systematic wheel-radius error (fraction)")
    w_bias: float = param(0.0, doc="gyro-like yaw drift while moving (rad/s)")

    def __post_init__(self) -> None:
        check_ranges(self)

    @classmethod
    def realistic(cls) -> OdomNoise:
        """A few percent of drift per metre: enough for SLAM to have something to correct."""
        return cls(v_scale_std=0.02, w_scale_std=0.02, v_add_std=0.005, w_add_std=0.01,
                   scale_bias=0.005, w_bias=0.002)

    @property
    def is_zero(self) -> bool:
        return not any(dataclasses.astuple(self))


@dataclass(frozen=True)
class OdomState:
    """Pose in the odom frame and body-frame velocities (nav_msgs/Odometry's twist is in base_link)."""

    x: float
    y: float
    yaw: float
    vx: float
    vy: float
    wz: float
    stamp: float = 0.0


class Odometry:
    def __init__(self, noise: OdomNoise, rng: np.random.Generator) -> None:
        self.noise, self.rng = noise, rng
        self._noisy = not noise.is_zero
        self.reset((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), 0.0)

    def reset(self, odom_pose: Pose2D, true_pose: Pose2D, t: float) -> None:
        self.pose: Pose2D = tuple(map(float, odom_pose))  # type: ignore[assignment]
        self.last_true: Pose2D = tuple(map(float, true_pose))  # type: ignore[assignment]
        self.last_t = t
        self.v_gain, self.w_gain = 1.0, 1.0

    def rebase(self, true_pose: Pose2D, t: float) -> None:
        """The true pose jumped (teleport): do not integrate the jump."""
        self.last_true, self.last_t = tuple(map(float, true_pose)), t  # type: ignore[assignment]

    def tick(self, true_pose: Pose2D, t: float) -> None:
        dt = t - self.last_t
        if dt <= 0:
            return
        delta = relative(self.last_true, true_pose)
        if self._noisy:
            delta = self._corrupt(delta, dt)
        self.pose = compose(self.pose, delta)
        self.last_true, self.last_t = true_pose, t

    def _corrupt(self, delta: Pose2D, dt: float) -> Pose2D:
        n, rng = self.noise, self.rng
        vx, vy, w = delta[0] / dt, delta[1] / dt, delta[2] / dt
        moving = math.hypot(vx, vy) > MOVING_EPS or abs(w) > MOVING_EPS
        self.v_gain = 1.0 + n.scale_bias + float(rng.normal(0.0, n.v_scale_std))
        self.w_gain = 1.0 + float(rng.normal(0.0, n.w_scale_std))
        ax, ay, aw = rng.normal(0.0, 1.0, 3) * (n.v_add_std, n.v_add_std, n.w_add_std)
        if not moving:
            ax = ay = aw = 0.0
        w_meas = w * self.w_gain + (aw + n.w_bias if moving else 0.0)
        return ((vx * self.v_gain + ax) * dt, (vy * self.v_gain + ay) * dt, w_meas * dt)

    def state(self, true_pose: Pose2D, body_vel: tuple[float, float, float], t: float) -> OdomState:
        """The last tick's pose extended by the (noise-free) motion since it, so a query between
        ticks is current; the extension is never integrated, so polling cannot change the drift."""
        p = compose(self.pose, relative(self.last_true, true_pose))
        return OdomState(p[0], p[1], p[2], body_vel[0] * self.v_gain,
                         body_vel[1] * self.v_gain, body_vel[2] * self.w_gain, t)
