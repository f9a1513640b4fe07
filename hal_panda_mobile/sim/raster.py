"""Rasterise scene prisms into an occupancy GridMap (ground truth for scoring SLAM maps, free-space checks)."""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence

import numpy as np

from robonix_common.grid import FREE, OCCUPIED, GridMap

from .scene import Obstacle
from .shapes import Circle, Rect


def rasterize(obstacles: Iterable[Obstacle], bounds: Sequence[float], resolution: float, *,
              inflate: float = 0.0, min_height: float = 0.0, overlap: bool = True) -> GridMap:
    """Occupied (100) where an obstacle covers a cell, free (0) elsewhere, over ``bounds``.

    ``overlap`` marks every cell the shape touches (shape grown by half a cell, so thin walls never
    vanish between cell centres); otherwise only cells whose centre lies inside. ``min_height`` skips
    prisms lower than e.g. the lidar plane; ``inflate`` grows every shape (free-space planning checks).
    """
    if not (resolution > 0 and math.isfinite(resolution)):
        raise ValueError(f"resolution must be > 0, got {resolution}")
    xmin, ymin, xmax, ymax = (float(b) for b in bounds)
    w = max(1, math.ceil((xmax - xmin) / resolution - 1e-9))
    h = max(1, math.ceil((ymax - ymin) / resolution - 1e-9))
    data = np.full((h, w), FREE, dtype=np.int8)
    grow = inflate + (resolution / 2 if overlap else 0.0)
    for ob in obstacles:
        if ob.height < min_height:
            continue
        s = ob.shape
        shape = (Rect(s.cx, s.cy, s.sx + 2 * grow, s.sy + 2 * grow, s.yaw) if isinstance(s, Rect)
                 else Circle(s.cx, s.cy, s.r + grow))
        ax0, ay0, ax1, ay1 = shape.aabb()
        c0, c1 = max(0, int((ax0 - xmin) / resolution)), min(w, int((ax1 - xmin) / resolution) + 1)
        r0, r1 = max(0, int((ay0 - ymin) / resolution)), min(h, int((ay1 - ymin) / resolution) + 1)
        if c0 >= c1 or r0 >= r1:
            continue
        xs = xmin + (np.arange(c0, c1) + 0.5) * resolution
        ys = ymin + (np.arange(r0, r1) + 0.5) * resolution
        gx, gy = np.meshgrid(xs, ys)
        data[r0:r1, c0:c1][shape.contains(gx, gy)] = OCCUPIED
    return GridMap(data, resolution, xmin, ymin)


def reachable(grid: GridMap, start: tuple[float, float], points: Iterable[tuple[float, float]]) -> list[bool]:
    """Which points are 8-connected to ``start`` through free cells of ``grid`` (an inflated raster)."""
    from scipy import ndimage  # here, not at the top: the HAL imports this module before it registers

    free = grid.data == FREE
    labels, _ = ndimage.label(free, structure=np.ones((3, 3), dtype=int))

    def label_at(p: tuple[float, float]) -> int:
        c, r = grid.world_to_cell(p[0], p[1])
        return int(labels[int(r), int(c)]) if bool(grid.in_bounds(c, r)) else 0

    s = label_at(start)
    return [s > 0 and label_at(p) == s for p in points]
