"""How close the robot's body came to the scene's obstacles, from the simulator's ground truth.

A contact is binary and rare, so a run without one says little about how much room was left; the
closest approach of the true footprint to the true obstacles does. It is measured from dense ground-truth
poses (`rbnx demo` records them from the HAL's ground-truth topic, the in-process pipeline at every control
tick) against the scene the simulator loaded, on a 2 cm raster: the distance of each footprint outline
point to the nearest occupied cell, 0 for a point inside one. Accuracy about one cell.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from robonix_common.grid import GridMap

RESOLUTION_M = 0.02


@dataclass(frozen=True)
class Closest:
    """The closest approach over a stretch of poses: clearance (m) and the ground-truth pose where it was."""

    clearance_m: float
    pose: tuple[float, float, float]

    def as_dict(self) -> dict[str, float]:
        return {"clearance_m": round(self.clearance_m, 3), "x": round(self.pose[0], 3), "y": round(self.pose[1], 3),
                "theta": round(self.pose[2], 3)}


class ClearanceField:
    """Distance to the nearest obstacle over a raster of the scene, and the footprint outline to probe it with."""

    def __init__(self, occupied: NDArray[np.bool_], origin: tuple[float, float], resolution: float,
                 footprint: Sequence[Sequence[float]], scene_name: str = "") -> None:
        from scipy.ndimage import distance_transform_edt

        self.origin, self.res, self.scene_name = origin, resolution, scene_name
        # cell centre to the nearest occupied cell's centre, less half a cell: to that cell's edge
        self.dist = np.maximum(distance_transform_edt(~occupied) * resolution - resolution / 2, 0.0)
        self.dist[occupied] = 0.0
        self.outline = _outline(np.asarray(footprint, dtype=float), resolution)

    @classmethod
    def for_scene(cls, scene_spec: str, resolution: float = RESOLUTION_M) -> ClearanceField:
        """The field for a scene as ``rbnx demo --scene`` names it (the simulator's own loader builds it)."""
        from hal_panda_mobile.files import load_robot_description
        from hal_panda_mobile.files.scene import load_scene
        from hal_panda_mobile.sim.raster import rasterize

        robot = load_robot_description()
        scene = load_scene(scene_spec, robot=robot, check=False)
        xmin, ymin, xmax, ymax = scene.bounds
        pad = 1.0
        grid = rasterize(scene.obstacles(), (xmin - pad, ymin - pad, xmax + pad, ymax + pad), resolution,
                         overlap=False)
        return cls.from_grid(grid, robot.footprint, scene.name)

    @classmethod
    def from_grid(cls, grid: GridMap, footprint: Sequence[Sequence[float]], scene_name: str = "") -> ClearanceField:
        """The field over an occupancy raster (occupied = 100) of the true obstacles, e.g. the simulator's
        ``ground_truth_grid(RESOLUTION_M, overlap=False)``."""
        return cls(grid.data >= 100, (grid.origin_x, grid.origin_y), grid.resolution, footprint, scene_name)

    def closest(self, poses: Sequence[Sequence[float]]) -> Closest | None:
        """The smallest outline clearance over ``poses`` (x, y, yaw); None for no poses."""
        if len(poses) == 0:
            return None
        p = np.asarray(poses, dtype=float)[:, :3]
        c, s = np.cos(p[:, 2:3]), np.sin(p[:, 2:3])
        px = p[:, 0:1] + c * self.outline[None, :, 0] - s * self.outline[None, :, 1]
        py = p[:, 1:2] + s * self.outline[None, :, 0] + c * self.outline[None, :, 1]
        col = np.clip(np.floor((px - self.origin[0]) / self.res).astype(int), 0, self.dist.shape[1] - 1)
        row = np.clip(np.floor((py - self.origin[1]) / self.res).astype(int), 0, self.dist.shape[0] - 1)
        per_pose = self.dist[row, col].min(axis=1)
        k = int(np.argmin(per_pose))
        return Closest(float(per_pose[k]), (float(p[k, 0]), float(p[k, 1]), float(p[k, 2])))


def _outline(polygon: NDArray[np.float64], spacing: float) -> NDArray[np.float64]:
    """Points along the polygon's edges no more than ``spacing`` apart (vertices included)."""
    pts = []
    for a, b in zip(polygon, np.roll(polygon, -1, axis=0), strict=True):
        n = max(1, math.ceil(float(np.hypot(*(b - a))) / spacing))
        pts.append(a + (b - a) * (np.arange(n)[:, None] / n))
    return np.vstack(pts)
