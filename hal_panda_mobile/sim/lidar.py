"""2-D lidar by ``mujoco.mj_multiRay`` from the mount pose.

Range convention (ROS REP-117): a valid return is in [range_min, range_max]; no return within
range_max, a dropout, or a noisy value pushed past range_max is ``+inf``; a return closer than
range_min is ``-inf``. Consumers must treat both infinities as "no obstacle measured there".

The beam fan is oriented by the lidar site's world rotation matrix (the base body's world rotation
composed with the mount): a heading read from a joint value misses any rotation of the body itself,
which is the bug OpenRAL shipped. The robot never sees itself: its body is excluded and its geoms sit
in a group the ray cast does not include.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray

from .robot import LidarSpec

VISIBLE_GROUPS = np.array([1, 0, 0, 0, 0, 0], dtype=np.uint8)  # obstacles only (group 0)


@dataclass(frozen=True)
class ScanResult:
    """One sweep, shaped like sensor_msgs/LaserScan (ranges float32, time_increment 0: instantaneous)."""

    angle_min: float
    angle_increment: float
    ranges: NDArray[np.float32]
    stamp: float  # sim seconds
    range_min: float
    range_max: float
    frame_id: str = "laser"

    @property
    def angle_max(self) -> float:
        return self.angle_min + (len(self.ranges) - 1) * self.angle_increment

    def angles(self) -> NDArray[np.float64]:
        return self.angle_min + np.arange(len(self.ranges)) * self.angle_increment


def beam_angles(spec: LidarSpec) -> tuple[float, float]:
    """(angle_min, increment): a full circle has no duplicated beam at +pi; a sector spans [-fov/2, fov/2]."""
    if spec.fov >= 2 * math.pi - 1e-9:
        return -math.pi, 2 * math.pi / spec.beams
    if spec.beams == 1:
        return 0.0, 0.0
    return -spec.fov / 2, spec.fov / (spec.beams - 1)


class Lidar:
    """Holds preallocated buffers so a sweep allocates almost nothing."""

    def __init__(self, model: mujoco.MjModel, spec: LidarSpec, site_id: int, exclude_body: int,
                 rng: np.random.Generator, noise_std: float, dropout_prob: float) -> None:
        self.model, self.spec, self.site_id, self.exclude_body = model, spec, site_id, exclude_body
        self.rng, self.noise_std, self.dropout_prob = rng, noise_std, dropout_prob
        self.angle_min, self.angle_increment = beam_angles(spec)
        a = self.angle_min + np.arange(spec.beams) * self.angle_increment
        self._local = np.stack([np.cos(a), np.sin(a), np.zeros_like(a)], axis=1)  # site frame
        self._vec = np.empty(3 * spec.beams)
        self._dist = np.empty(spec.beams)
        self._geomid = np.empty(spec.beams, dtype=np.int32)

    def scan(self, data: mujoco.MjData, stamp: float) -> ScanResult:
        """Cast the fan; ``data`` must have current kinematics (site_xpos/site_xmat, geom poses)."""
        n, spec = self.spec.beams, self.spec
        rot = data.site_xmat[self.site_id].reshape(3, 3)
        np.matmul(self._local, rot.T, out=self._vec.reshape(n, 3))
        pnt = data.site_xpos[self.site_id].copy()
        mujoco.mj_multiRay(self.model, data, pnt, self._vec, VISIBLE_GROUPS, 1, self.exclude_body,
                           self._geomid, self._dist, None, n, spec.range_max)
        r = self._dist.copy()
        hit = self._geomid >= 0
        if self.noise_std > 0:
            r[hit] += self.rng.normal(0.0, self.noise_std, int(hit.sum()))
        out = np.full(n, np.inf)
        out[hit] = r[hit]
        out[hit & (r < spec.range_min)] = -np.inf
        out[out > spec.range_max] = np.inf
        if self.dropout_prob > 0:
            out[self.rng.random(n) < self.dropout_prob] = np.inf
        return ScanResult(self.angle_min, self.angle_increment, out.astype(np.float32), stamp,
                          spec.range_min, spec.range_max, spec.frame)
