"""Escape motions for a wedged holonomic base, chosen from the true footprint clearance.

Why not a fixed back-up: in dense clutter the base wedges a few centimetres from a post, and body-backwards
often points at another post. The footprint is a 0.70 × 0.50 m rectangle, so which way is free depends on
the exact geometry around it. Here every short holonomic motion (a direction over the full circle, a short
translation, a small rotation, or both) is simulated with the footprint polygon against the obstacles that
are really there — the local costmap's lethal cells and the latest scan points — and the one that most
increases the polygon's clearance wins, ties going toward the path.

Clearance is a signed distance: from the footprint polygon to the nearest obstacle point (a lethal cell is a
disc of half a cell, a scan return a point), negative when a point lies inside the polygon. Pure numpy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from robonix_common.geometry import Pose2D, wrap_angle
from robonix_common.scan import Scan

from .costmap import Costmap
from .costs import LETHAL

#: Poses evaluated per chunk when measuring clearance (bounds the (poses × points × edges) temporaries).
_CHUNK = 256


@dataclass(frozen=True)
class Obstacles:
    """Obstacle points in the costmap frame (M, 2) with a radius each (M,): what clearance is measured to."""

    points: NDArray[np.float64]
    radii: NDArray[np.float64]

    @classmethod
    def empty(cls) -> Obstacles:
        return cls(np.zeros((0, 2)), np.zeros(0))

    def near(self, x: float, y: float, reach: float) -> Obstacles:
        keep = np.hypot(self.points[:, 0] - x, self.points[:, 1] - y) <= reach + self.radii
        return Obstacles(self.points[keep], self.radii[keep])


def scan_points(scan: Scan, sensor_pose: Pose2D, max_range: float = 3.0) -> NDArray[np.float64]:
    """The scan's valid returns within ``max_range`` as world points (M, 2); the escape only looks nearby."""
    r = np.asarray(scan.ranges, dtype=float)
    ang = scan.angles + float(sensor_pose[2])
    ok = np.isfinite(r) & (r >= scan.range_min) & (r <= min(scan.range_max, max_range))
    return np.stack([sensor_pose[0] + r[ok] * np.cos(ang[ok]), sensor_pose[1] + r[ok] * np.sin(ang[ok])], axis=1)


def gather_obstacles(costmap: Costmap, x: float, y: float, reach: float,
                     scan_pts: NDArray[np.float64] | None = None) -> Obstacles:
    """Lethal cells of ``costmap`` (as discs of half a cell) and scan points within ``reach`` of (x, y)."""
    res = costmap.resolution
    c0, r0 = costmap.world_to_cell(x - reach, y - reach)
    c1, r1 = costmap.world_to_cell(x + reach, y + reach)
    rows, cols = costmap.shape
    r0, r1, c0, c1 = max(0, int(r0)), min(rows, int(r1) + 1), max(0, int(c0)), min(cols, int(c1) + 1)
    pts = [np.zeros((0, 2))]
    rad = [np.zeros(0)]
    if r1 > r0 and c1 > c0:
        rr, cc = np.nonzero(costmap.costs[r0:r1, c0:c1] == LETHAL)
        wx, wy = costmap.cell_to_world(cc + c0, rr + r0)
        pts.append(np.stack([wx, wy], axis=1))
        rad.append(np.full(len(rr), 0.5 * res))
    if scan_pts is not None and len(scan_pts):
        pts.append(np.asarray(scan_pts, dtype=float).reshape(-1, 2))
        rad.append(np.zeros(len(pts[-1])))
    return Obstacles(np.vstack(pts), np.concatenate(rad)).near(x, y, reach)


def clearance(polygon: NDArray[np.float64], poses: NDArray[np.float64], obs: Obstacles) -> NDArray[np.float64]:
    """Signed clearance of the footprint ``polygon`` (base frame, (E, 2)) at each pose (N, 3) to ``obs``:
    the smallest polygon-to-obstacle distance, negative for an obstacle inside. +inf with no obstacles."""
    poses = np.atleast_2d(np.asarray(poses, dtype=float))
    if len(obs.points) == 0:
        return np.full(len(poses), np.inf)
    out = np.empty(len(poses))
    for k in range(0, len(poses), _CHUNK):
        out[k:k + _CHUNK] = _clearance_chunk(polygon, poses[k:k + _CHUNK], obs)
    return out


def _clearance_chunk(polygon: NDArray[np.float64], poses: NDArray[np.float64], obs: Obstacles) -> NDArray:
    c, s = np.cos(poses[:, 2])[:, None], np.sin(poses[:, 2])[:, None]
    dx = obs.points[None, :, 0] - poses[:, 0:1]
    dy = obs.points[None, :, 1] - poses[:, 1:2]
    bx, by = c * dx + s * dy, -s * dx + c * dy                     # (N, M) obstacle points in the base frame
    a, b = polygon, np.roll(polygon, -1, axis=0)
    ex, ey = b[:, 0] - a[:, 0], b[:, 1] - a[:, 1]                  # (E,)
    px, py = bx[..., None] - a[:, 0], by[..., None] - a[:, 1]      # (N, M, E)
    t = np.clip((px * ex + py * ey) / np.maximum(ex * ex + ey * ey, 1e-12), 0.0, 1.0)
    d = np.hypot(px - t * ex, py - t * ey).min(axis=2)
    crosses = ((a[:, 1] > by[..., None]) != (b[:, 1] > by[..., None])) & \
        (bx[..., None] < a[:, 0] + (by[..., None] - a[:, 1]) * ex / np.where(ey == 0, 1e-12, ey))
    inside = np.count_nonzero(crosses, axis=2) % 2 == 1
    return (np.where(inside, -d, d) - obs.radii[None, :]).min(axis=1)


@dataclass(frozen=True)
class Motion:
    """A short motion from ``start``: a world-frame translation (dx, dy) and a rotation dth, done together
    along a straight line (what the escape commands, re-aimed at the target pose every step)."""

    dx: float
    dy: float
    dth: float

    def poses(self, start: Pose2D, samples: int) -> NDArray[np.float64]:
        f = np.linspace(0.0, 1.0, samples + 1)[1:, None]
        return np.asarray(start, dtype=float)[None, :] + f * np.array([self.dx, self.dy, self.dth])[None, :]

    def describe(self) -> str:
        d = math.hypot(self.dx, self.dy)
        move = f"{d:.2f} m toward {math.degrees(math.atan2(self.dy, self.dx)):.0f}°" if d > 1e-6 else ""
        turn = f"turn {math.degrees(self.dth):+.0f}°" if abs(self.dth) > 1e-6 else ""
        return " and ".join(p for p in (move, turn) if p) or "stay"


@dataclass(frozen=True)
class Choice:
    motion: Motion | None     # None: no motion is free
    start_clearance: float
    end_clearance: float
    candidates: int
    free: int


def candidate_motions(dist: float, turn: float, directions: int) -> list[Motion]:
    """Translations of ``dist`` and ``dist / 2`` in ``directions`` world directions, each with no turn or
    ``±turn``, plus turning in place by ``±turn`` and ``±2 turn``."""
    out = []
    for k in range(directions):
        a = 2.0 * math.pi * k / directions
        for d in (dist, 0.5 * dist):
            for r in (0.0, turn, -turn):
                out.append(Motion(d * math.cos(a), d * math.sin(a), r))
    out += [Motion(0.0, 0.0, r) for r in (turn, -turn, 2 * turn, -2 * turn)]
    return out


def samples_for(motions: list[Motion], circumscribed: float, step: float) -> int:
    """Samples along a motion so that no footprint point moves more than ``step`` between two of them."""
    sweep = max((math.hypot(m.dx, m.dy) + abs(m.dth) * circumscribed for m in motions), default=0.0)
    return max(2, int(math.ceil(sweep / step)))


def allowed_floor(start_clearance: float, margin: float, tolerance: float) -> float:
    """The smallest clearance a motion may pass through: never closer than the margin, or than the robot
    already is when it is inside the margin (minus a noise tolerance) — a wedged base may slide along a post
    it nearly touches, but not toward it."""
    return min(start_clearance, margin) - tolerance


def choose(polygon: NDArray[np.float64], pose: Pose2D, obs: Obstacles, motions: list[Motion], *, margin: float,
           tolerance: float, enough: float, aim: tuple[float, float] | None, step: float = 0.01) -> Choice:
    """The free motion (clearance never below :func:`allowed_floor` on the way) whose end pose has the most
    clearance, counted up to ``enough``; among those within a centimetre, the one most along ``aim`` (a
    world direction: the path's or the goal's)."""
    circ = float(np.max(np.hypot(polygon[:, 0], polygon[:, 1])))
    n = samples_for(motions, circ, step)
    c0 = float(clearance(polygon, np.array([pose]), obs)[0])
    floor = allowed_floor(c0, margin, tolerance)
    poses = np.concatenate([m.poses(pose, n) for m in motions])
    cl = clearance(polygon, poses, obs).reshape(len(motions), n)
    free = cl.min(axis=1) >= floor
    if not free.any():
        return Choice(None, c0, c0, len(motions), 0)
    end = np.minimum(cl[:, -1], enough)
    if aim is not None and math.hypot(*aim) > 1e-9:
        u = np.asarray(aim, dtype=float) / math.hypot(*aim)
        along = np.array([(m.dx * u[0] + m.dy * u[1]) / max(math.hypot(m.dx, m.dy), 1e-9) for m in motions])
    else:
        along = np.zeros(len(motions))
    score = np.round(end / 0.01) + 0.5 * along              # clearance in whole cm first, then direction
    k = int(np.argmax(np.where(free, score, -np.inf)))
    return Choice(motions[k], c0, float(cl[k, -1]), len(motions), int(free.sum()))


def blocked_toward(polygon: NDArray[np.float64], pose: Pose2D, obs: Obstacles, direction: tuple[float, float],
                   margin: float, probe: float = 0.03) -> bool:
    """Whether the footprint is within ``margin`` of an obstacle and a ``probe`` step along ``direction``
    (world frame) would bring it closer still: the base is pressed against something on its way."""
    n = math.hypot(*direction)
    if n < 1e-9:
        return False
    ux, uy = direction[0] / n, direction[1] / n
    poses = np.array([pose, (pose[0] + probe * ux, pose[1] + probe * uy, pose[2])], dtype=float)
    c = clearance(polygon, poses, obs)
    return bool(c[0] < margin and c[1] < margin and c[1] <= c[0] + 1e-4)


def body_command(pose: Pose2D, target: Pose2D, speed: float, turn_rate: float,
                 dt: float) -> tuple[float, float, float]:
    """Body-frame (vx, vy, wz) that heads straight for ``target`` and arrives with translation and rotation
    finishing together, no faster than ``speed`` / ``turn_rate`` and without overshooting within ``dt``."""
    dx, dy = target[0] - pose[0], target[1] - pose[1]
    dth = float(wrap_angle(target[2] - pose[2]))
    t = max(math.hypot(dx, dy) / speed, abs(dth) / turn_rate, dt)
    vx_w, vy_w, wz = dx / t, dy / t, dth / t
    c, s = math.cos(pose[2]), math.sin(pose[2])
    return c * vx_w + s * vy_w, -s * vx_w + c * vy_w, wz
