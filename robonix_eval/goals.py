"""Seeded random goals that a robot with this footprint can actually reach: benchmarks need goals that are
hard only because of navigation, never because they are impossible."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from scipy import ndimage

from hal_panda_mobile.sim import PandaMobileSim
from robonix_common.grid import FREE


def sample_goals(sim: PandaMobileSim, n: int, seed: int, *, start: Sequence[float] | None = None,
                 clearance: float = 0.15, min_separation: float = 2.0, resolution: float = 0.05,
                 max_tries: int = 20000) -> list[tuple[float, float, float]]:
    """``n`` goals (x, y, yaw) on the sim's ground truth, in the order they will be driven.

    Each goal leaves ``clearance`` around the circumscribed footprint (any final yaw fits), is connected
    to ``start`` through space the inscribed footprint passes (plus the same clearance), and lies at
    least ``min_separation`` from the previous goal (the start for the first). Raises if the scene
    cannot supply them.
    """
    robot = sim.robot
    start = tuple(start) if start is not None else sim.ground_truth()[:2]
    r_out = robot.footprint_radius + clearance
    r_in = min(max(abs(x) for x, _ in robot.footprint), max(abs(y) for _, y in robot.footprint)) + clearance
    roomy = sim.ground_truth_grid(resolution, inflate=r_out).data == FREE
    passable = sim.ground_truth_grid(resolution, inflate=r_in)
    labels, _ = ndimage.label(passable.data == FREE, structure=np.ones((3, 3), dtype=int))
    sc, sr = passable.world_to_cell(start[0], start[1])
    if not bool(passable.in_bounds(sc, sr)) or labels[int(sr), int(sc)] == 0:
        raise ValueError(f"start {start[:2]} is not in free space with clearance {clearance} m")
    rows, cols = np.nonzero(roomy & (labels == labels[int(sr), int(sc)]))
    if len(rows) == 0:
        raise ValueError("no reachable cell has the requested clearance")
    xs, ys = passable.cell_to_world(cols, rows)
    rng = np.random.default_rng(seed)
    goals: list[tuple[float, float, float]] = []
    prev = (float(start[0]), float(start[1]))
    for _ in range(max_tries):
        if len(goals) == n:
            break
        i = int(rng.integers(len(xs)))
        x, y = float(xs[i]), float(ys[i])
        yaw = float(rng.uniform(-math.pi, math.pi))
        if math.hypot(x - prev[0], y - prev[1]) < min_separation:
            continue
        goals.append((round(x, 3), round(y, 3), round(yaw, 3)))
        prev = (x, y)
    if len(goals) < n:
        raise ValueError(f"only {len(goals)} of {n} goals found with separation {min_separation} m")
    return goals
