"""Pure-numpy 2D worlds for tests and the benchmark: rectangles, a ray caster, a scripted drive and a
drifting odometry. Independent of the MuJoCo simulator so the SLAM core can be validated alone and
deterministically (everything is seeded).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from robonix_common.geometry import compose, relative, wrap_angle
from robonix_common.grid import GridMap
from slam_service.core import Scan

Rect = tuple[float, float, float, float]  # x0, y0, x1, y1


@dataclass
class World:
    """Axis-aligned solid rectangles (walls, furniture) and a drive through them."""

    name: str
    rects: list[Rect]
    waypoints: list[tuple[float, float]]
    segments: NDArray[np.float64] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        segs = []
        for x0, y0, x1, y1 in self.rects:
            segs += [(x0, y0, x1, y0), (x1, y0, x1, y1), (x1, y1, x0, y1), (x0, y1, x0, y0)]
        self.segments = np.asarray(segs, dtype=np.float64)

    def bounds(self) -> tuple[float, float, float, float]:
        r = np.asarray(self.rects)
        return float(r[:, 0].min()), float(r[:, 1].min()), float(r[:, 2].max()), float(r[:, 3].max())

    def ground_truth_grid(self, resolution: float = 0.05, margin: float = 0.5) -> GridMap:
        """Cells whose centre lies inside a rectangle are occupied (100), all others free (0)."""
        x0, y0, x1, y1 = self.bounds()
        ox, oy = x0 - margin, y0 - margin
        w = int(math.ceil((x1 - x0 + 2 * margin) / resolution))
        h = int(math.ceil((y1 - y0 + 2 * margin) / resolution))
        xc = ox + (np.arange(w) + 0.5) * resolution
        yc = oy + (np.arange(h) + 0.5) * resolution
        data = np.zeros((h, w), dtype=np.int8)
        for rx0, ry0, rx1, ry1 in self.rects:
            cols = (xc >= rx0) & (xc <= rx1)
            rows = (yc >= ry0) & (yc <= ry1)
            data[np.ix_(rows, cols)] = 100
        return GridMap(data, resolution, ox, oy)

    def raycast(self, pose: NDArray, angles: NDArray, max_range: float) -> NDArray[np.float64]:
        """Distance along each beam to the first segment (inf when nothing within max_range)."""
        ox, oy = float(pose[0]), float(pose[1])
        dx, dy = np.cos(angles)[:, None], np.sin(angles)[:, None]
        s = self.segments
        ex, ey = (s[:, 2] - s[:, 0])[None, :], (s[:, 3] - s[:, 1])[None, :]
        px, py = (s[:, 0] - ox)[None, :], (s[:, 1] - oy)[None, :]
        den = dx * ey - dy * ex
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (px * ey - py * ex) / den
            u = (px * dy - py * dx) / den
        ok = (np.abs(den) > 1e-12) & (t > 1e-9) & (u >= 0) & (u <= 1)
        t = np.where(ok, t, np.inf).min(axis=1)
        t[t > max_range] = np.inf
        return t


def apartment_world() -> World:
    """10 x 8 m flat: four rooms joined by doorways in a ring, asymmetric furniture, thin walls."""
    t = 0.1
    rects: list[Rect] = [
        (0.0, 0.0, 10.0, t), (0.0, 8.0 - t, 10.0, 8.0), (0.0, 0.0, t, 8.0), (10.0 - t, 0.0, 10.0, 8.0),
        # vertical wall x=5 with doors at y 1.5-2.5 and 5.5-6.5
        (4.95, 0.0, 5.05, 1.5), (4.95, 2.5, 5.05, 5.5), (4.95, 6.5, 5.05, 8.0),
        # horizontal wall y=4 with doors at x 2-3 and 7-8
        (0.0, 3.95, 2.0, 4.05), (3.0, 3.95, 7.0, 4.05), (8.0, 3.95, 10.0, 4.05),
        # furniture
        (0.4, 2.6, 1.6, 3.4),  # sofa, room A
        (3.8, 0.4, 4.5, 0.9),  # cabinet, room A
        (8.6, 0.3, 9.6, 1.5),  # bed, room B
        (6.0, 0.3, 6.4, 0.7),  # nightstand, room B
        (8.8, 6.0, 9.6, 7.6),  # kitchen counter, room C
        (5.6, 7.2, 6.6, 7.6),  # fridge, room C
        (6.6, 5.0, 6.8, 5.2),  # table leg/column, room C
        (1.0, 6.4, 2.2, 7.2),  # dining table, room D
        (0.3, 4.4, 0.7, 4.8),  # plant, room D
        (3.9, 7.2, 4.6, 7.8),  # shelf, room D
    ]
    way = [(1.5, 1.5), (3.2, 1.8), (5.0, 2.0), (6.5, 2.0), (7.5, 2.8), (7.5, 4.0), (7.5, 5.2), (6.8, 6.0),
           (5.0, 6.0), (3.4, 6.0), (2.5, 5.0), (2.5, 4.0), (2.5, 2.6), (1.5, 1.6), (3.2, 1.8), (5.0, 2.0),
           (6.5, 2.0)]
    return World("apartment", rects, way)


def warehouse_world() -> World:
    """30 x 20 m hall with shelf rows and aisles; the drive loops around a shelf block."""
    t = 0.15
    rects: list[Rect] = [(0.0, 0.0, 30.0, t), (0.0, 20.0 - t, 30.0, 20.0), (0.0, 0.0, t, 20.0),
                         (30.0 - t, 0.0, 30.0, 20.0)]
    for i in range(4):
        y = 4.0 + 3.5 * i
        rects.append((5.0, y, 13.0 + 1.5 * i, y + 1.0))
        rects.append((17.0, y, 25.0 - i, y + 1.0))
    rects += [(1.0, 1.0, 2.0, 2.0), (27.0, 17.0, 28.5, 18.5), (14.5, 17.5, 15.5, 18.5), (28.0, 2.0, 29.0, 3.0)]
    way = [(3.0, 2.5), (15.0, 2.5), (27.0, 2.5), (27.0, 10.0), (27.0, 17.0), (15.0, 17.0), (3.0, 17.0),
           (3.0, 10.0), (3.0, 2.8), (15.0, 2.5), (20.0, 2.5)]
    return World("warehouse", rects, way)


@dataclass
class OdomDrift:
    """Odometry error model: scale errors, a heading bias per metre, white noise per step."""

    trans_scale: float = 0.02
    rot_scale: float = 0.02
    rot_bias_per_m: float = 0.01
    sigma_xy: float = 0.002
    sigma_theta: float = 0.002


@dataclass
class Recording:
    gt: NDArray[np.float64]  # (N, 3) ground-truth base poses
    odom: NDArray[np.float64]  # (N, 3) drifting odometry poses (odom frame = world frame at t=0)
    scans: list[Scan]
    stamps: NDArray[np.float64]


def drive(world: World, *, speed: float = 0.4, rate_hz: float = 10.0, max_yaw_rate: float = 1.2,
          beams: int = 360, range_max: float = 12.0, range_noise: float = 0.01, dropout: float = 0.0,
          odom_noise: OdomDrift | None = None, seed: int = 0, mount: tuple[float, float, float] = (0, 0, 0),
          ) -> Recording:
    """Drive the waypoints (holonomic, facing the direction of travel) and record scans + odometry."""
    rng = np.random.default_rng(seed)
    on = odom_noise or OdomDrift()
    dt = 1.0 / rate_hz
    wp = np.asarray(world.waypoints, dtype=float)
    poses = []
    pos = wp[0].copy()
    d0 = wp[1] - wp[0]
    yaw = math.atan2(d0[1], d0[0])
    for target in wp[1:]:
        while True:
            d = target - pos
            dist = float(np.hypot(*d))
            if dist < 1e-6:
                break
            want = math.atan2(d[1], d[0])
            yaw = float(wrap_angle(yaw + np.clip(wrap_angle(want - yaw), -max_yaw_rate * dt, max_yaw_rate * dt)))
            poses.append((pos[0], pos[1], yaw))
            pos = pos + d * min(1.0, speed * dt / dist)
    poses.append((pos[0], pos[1], yaw))
    gt = np.asarray(poses)
    odom = np.zeros_like(gt)
    odom[0] = gt[0]
    for k in range(1, len(gt)):
        dlt = relative(gt[k - 1], gt[k])
        step = math.hypot(dlt[0], dlt[1])
        noisy = np.array([
            dlt[0] * (1 + on.trans_scale) + rng.normal(0, on.sigma_xy),
            dlt[1] * (1 + on.trans_scale) + rng.normal(0, on.sigma_xy),
            dlt[2] * (1 + on.rot_scale) + on.rot_bias_per_m * step + rng.normal(0, on.sigma_theta),
        ])
        odom[k] = compose(odom[k - 1], noisy)
    ang_min = -math.pi
    inc = 2 * math.pi / beams
    angles = ang_min + inc * np.arange(beams)
    scans = []
    for k, p in enumerate(gt):
        sensor = compose(p, np.asarray(mount, dtype=float))
        r = world.raycast(sensor, angles + sensor[2], range_max)
        r = r + rng.normal(0, range_noise, r.shape) * np.isfinite(r)
        if dropout > 0:
            r[rng.random(r.shape) < dropout] = np.nan
        scans.append(Scan(r.astype(np.float32), ang_min, inc, 0.05, range_max, k * dt, tuple(mount)))
    return Recording(gt, odom, scans, np.arange(len(gt)) * dt)
