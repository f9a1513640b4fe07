"""Occupancy grids in ROS conventions, shared by SLAM (writes maps), navigation (reads ``/map``) and
the HAL (``from_map`` scenes), so all three agree on one convention:

* ``data`` is an ``int8`` array of shape ``(height, width)``; row ``r`` is ``y = origin_y + (r + .5) * res``
  (row 0 at the bottom, as in ``nav_msgs/OccupancyGrid``), values ``-1`` unknown, ``0..100`` occupancy.
* ``origin`` is the world pose of the corner of cell (0, 0); a non-zero yaw is kept but rarely used.

Pure numpy: the algorithm cores import it; map files live in :mod:`robonix_api.mapfile`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

UNKNOWN = -1
FREE = 0
OCCUPIED = 100


@dataclass
class GridMap:
    data: NDArray[np.int8]
    resolution: float
    origin_x: float = 0.0
    origin_y: float = 0.0
    origin_yaw: float = 0.0
    frame_id: str = "map"

    def __post_init__(self) -> None:
        self.data = np.asarray(self.data, dtype=np.int8)
        if self.data.ndim != 2:
            raise ValueError(f"GridMap.data must be 2-D (height, width), got shape {self.data.shape}")
        if not (self.resolution > 0 and math.isfinite(self.resolution)):
            raise ValueError(f"GridMap.resolution must be a positive number, got {self.resolution}")

    @property
    def height(self) -> int:
        return int(self.data.shape[0])

    @property
    def width(self) -> int:
        return int(self.data.shape[1])

    def world_to_cell(self, x: NDArray | float, y: NDArray | float) -> tuple[NDArray, NDArray]:
        """World coordinates -> (col, row) integer indices (may be out of bounds)."""
        c, s = math.cos(-self.origin_yaw), math.sin(-self.origin_yaw)
        dx = np.asarray(x, dtype=float) - self.origin_x
        dy = np.asarray(y, dtype=float) - self.origin_y
        lx, ly = c * dx - s * dy, s * dx + c * dy
        return np.floor(lx / self.resolution).astype(np.int64), np.floor(ly / self.resolution).astype(np.int64)

    def cell_to_world(self, col: NDArray | int, row: NDArray | int) -> tuple[NDArray, NDArray]:
        """Cell indices -> world coordinates of the cell centres."""
        lx = (np.asarray(col, dtype=float) + 0.5) * self.resolution
        ly = (np.asarray(row, dtype=float) + 0.5) * self.resolution
        c, s = math.cos(self.origin_yaw), math.sin(self.origin_yaw)
        return self.origin_x + c * lx - s * ly, self.origin_y + s * lx + c * ly

    def in_bounds(self, col: NDArray | int, row: NDArray | int) -> NDArray[np.bool_]:
        col, row = np.asarray(col), np.asarray(row)
        return (col >= 0) & (col < self.width) & (row >= 0) & (row < self.height)


def merge_cells(occ: np.ndarray) -> list[tuple[int, int, int, int]]:
    """Occupied cells -> rectangles (row0, row1, col0, col1), half-open: runs per row, stacked upward
    while the next row has exactly the same run. Far fewer geoms than one box per cell."""
    done: list[tuple[int, int, int, int]] = []
    open_runs: dict[tuple[int, int], int] = {}  # (c0, c1) -> first row
    for r in range(occ.shape[0] + 1):
        runs: set[tuple[int, int]] = set()
        if r < occ.shape[0]:
            row = np.concatenate(([False], occ[r], [False])).astype(np.int8)
            edges = np.flatnonzero(np.diff(row))
            runs = {(int(a), int(b)) for a, b in zip(edges[::2], edges[1::2], strict=True)}
        for run in list(open_runs):
            if run not in runs:
                done.append((open_runs.pop(run), r, run[0], run[1]))
        for run in runs:
            open_runs.setdefault(run, r)
    return done
