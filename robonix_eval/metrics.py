"""Ground-truth references for scoring runs: the shortest feasible path and trajectory helpers."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from nav2_wrapper.core import Costmap, CostmapConfig, Footprint, GlobalPlanner, PlannerConfig
from nav2_wrapper.robot_io import load_footprint
from robonix_common.grid import GridMap


class ShortestPaths:
    """Geometric shortest paths on a ground-truth grid in the robot's configuration space.

    The nav core's planner with no cost term (pure length), an admissible heuristic and shortcutting,
    on a costmap whose inscribed band is blocked: the reference a driven path is compared against.
    """

    def __init__(self, grid: GridMap, footprint: Footprint | None = None) -> None:
        cfg = CostmapConfig(name="ground_truth", resolution=grid.resolution, obstacle_layer=False,
                            observation_sources=[], footprint=footprint or load_footprint())
        self.costmap = Costmap(cfg)
        self.costmap.set_static_map(grid)
        self.planner = GlobalPlanner(PlannerConfig(tolerance=0.0, allow_unknown=False, cost_travel_multiplier=0.0,
                                                   heuristic_weight=1.0, smooth_path=True, smoothing_slack=0.0))

    def length(self, start: Sequence[float], goal: Sequence[float]) -> float:
        """Metres of the shortest feasible path, or NaN when there is none."""
        res = self.planner.plan(self.costmap, (float(start[0]), float(start[1])), (float(goal[0]), float(goal[1])))
        return res.length if res.ok else math.nan


def path_length(points: NDArray[np.float64] | Sequence[Sequence[float]]) -> float:
    p = np.asarray(points, dtype=float).reshape(-1, 2)
    return float(np.sum(np.hypot(*np.diff(p, axis=0).T))) if len(p) > 1 else 0.0


def yaw_error(a: float, b: float) -> float:
    return abs(math.remainder(a - b, 2 * math.pi))
