"""2-D footprints of the world's prisms (every obstacle is an extruded rectangle or circle).

One geometry used everywhere the sim needs it without MuJoCo: start-pose/teleport/spawn checks,
ground-truth rasterisation, scene info. Numpy only.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray


@dataclass(frozen=True)
class Rect:
    """Rectangle: centre, full sizes along its own axes, yaw."""

    cx: float
    cy: float
    sx: float
    sy: float
    yaw: float = 0.0

    def corners(self) -> NDArray[np.float64]:
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        hx, hy = self.sx / 2, self.sy / 2
        local = np.array([[hx, hy], [-hx, hy], [-hx, -hy], [hx, -hy]])
        return local @ np.array([[c, s], [-s, c]]) + (self.cx, self.cy)

    def contains(self, x: NDArray, y: NDArray) -> NDArray[np.bool_]:
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        dx, dy = np.asarray(x) - self.cx, np.asarray(y) - self.cy
        lx, ly = c * dx + s * dy, -s * dx + c * dy
        return (np.abs(lx) <= self.sx / 2) & (np.abs(ly) <= self.sy / 2)

    def aabb(self) -> tuple[float, float, float, float]:
        p = self.corners()
        return float(p[:, 0].min()), float(p[:, 1].min()), float(p[:, 0].max()), float(p[:, 1].max())


@dataclass(frozen=True)
class Circle:
    cx: float
    cy: float
    r: float

    def contains(self, x: NDArray, y: NDArray) -> NDArray[np.bool_]:
        return (np.asarray(x) - self.cx) ** 2 + (np.asarray(y) - self.cy) ** 2 <= self.r**2

    def aabb(self) -> tuple[float, float, float, float]:
        return self.cx - self.r, self.cy - self.r, self.cx + self.r, self.cy + self.r


Shape = Rect | Circle


def _seg_point_dist(a: NDArray, b: NDArray, p: NDArray) -> float:
    ab = b - a
    t = float(np.clip(np.dot(p - a, ab) / max(float(np.dot(ab, ab)), 1e-18), 0.0, 1.0))
    return float(np.linalg.norm(a + t * ab - p))


def _poly_overlap(p: NDArray, q: NDArray) -> bool:
    """Separating-axis test for two convex polygons."""
    for poly in (p, q):
        edges = np.roll(poly, -1, axis=0) - poly
        for nx, ny in np.stack([-edges[:, 1], edges[:, 0]], axis=1):
            pa, qa = p @ (nx, ny), q @ (nx, ny)
            if pa.max() < qa.min() or qa.max() < pa.min():
                return False
    return True


def _point_in_convex(poly: NDArray, pt: NDArray) -> bool:
    edges = np.roll(poly, -1, axis=0) - poly
    rel = pt - poly
    cross = edges[:, 0] * rel[:, 1] - edges[:, 1] * rel[:, 0]
    return bool(np.all(cross >= 0) or np.all(cross <= 0))


def polygon_distance(poly: NDArray, shape: Shape) -> float:
    """Distance between a convex polygon and a shape; 0 when they touch or overlap."""
    poly = np.asarray(poly, dtype=float)
    if isinstance(shape, Circle):
        c = np.array([shape.cx, shape.cy])
        if _point_in_convex(poly, c):
            return 0.0
        d = min(_seg_point_dist(poly[i], poly[(i + 1) % len(poly)], c) for i in range(len(poly)))
        return max(0.0, d - shape.r)
    q = shape.corners()
    if _poly_overlap(poly, q):
        return 0.0
    best = math.inf
    for a, b in ((poly, q), (q, poly)):
        for i in range(len(b)):
            for pt in a:
                best = min(best, _seg_point_dist(b[i], b[(i + 1) % len(b)], pt))
    return best


def convex_hull(points: NDArray) -> NDArray[np.float64]:
    """Counter-clockwise hull (monotone chain); the robot polygon is treated as convex."""
    pts = sorted({(float(x), float(y)) for x, y in np.asarray(points)})

    def half(seq: list[tuple[float, float]]) -> list[tuple[float, float]]:
        out: list[tuple[float, float]] = []
        for p in seq:
            while len(out) >= 2 and ((out[-1][0] - out[-2][0]) * (p[1] - out[-2][1])
                                     - (out[-1][1] - out[-2][1]) * (p[0] - out[-2][0])) <= 0:
                out.pop()
            out.append(p)
        return out

    lower, upper = half(pts), half(pts[::-1])
    return np.array(lower[:-1] + upper[:-1])
