"""MPPI controller core: drives a kinematic omni base along a path, around clutter, reproducibly."""

from __future__ import annotations

import math

import numpy as np
import pytest

from nav2_wrapper.core.controller import ControllerConfig
from nav2_wrapper.core.costmap import Costmap, CostmapConfig
from nav2_wrapper.core.costs import LETHAL
from nav2_wrapper.core.footprint import Footprint
from nav2_wrapper.core.mppi import MppiConfig, MppiController
from robonix_common.grid import GridMap

RES = 0.05
FOOTPRINT = Footprint(np.array([[0.35, 0.25], [-0.35, 0.25], [-0.35, -0.25], [0.35, -0.25]]))


def _costmap(posts: list[tuple[float, float]]) -> Costmap:
    grid = np.zeros((120, 160), np.int8)   # 8 m × 6 m
    grid[0, :] = grid[-1, :] = 100
    grid[:, 0] = grid[:, -1] = 100
    for x, y in posts:
        c, r = int(x / RES), int(y / RES)
        grid[r - 1:r + 2, c - 1:c + 2] = 100   # 0.15 m post
    cm = Costmap(CostmapConfig(obstacle_layer=False, footprint=FOOTPRINT, inflation_radius=0.55,
                               cost_scaling_factor=3.0))
    cm.set_static_map(GridMap(grid, RES))
    return cm


def _drive(ctl: MppiController, cm: Costmap, start: tuple[float, float, float], goal: tuple[float, float, float],
           steps: int = 400, dt: float = 0.05) -> tuple[list[tuple[float, float, float]], list[tuple[float, ...]]]:
    """Integrate the commands exactly (a perfect omni base) and record poses and commands."""
    pose, vel = start, (0.0, 0.0, 0.0)
    poses, cmds = [pose], []
    for _ in range(steps):
        out = ctl.compute(pose, vel, goal, cm, dt)
        c, s = math.cos(pose[2]), math.sin(pose[2])
        pose = (pose[0] + (c * out.vx - s * out.vy) * dt, pose[1] + (s * out.vx + c * out.vy) * dt,
                pose[2] + out.wz * dt)
        vel = (out.vx, out.vy, out.wz)
        poses.append(pose)
        cmds.append((out.vx, out.vy, out.wz))
        if math.hypot(goal[0] - pose[0], goal[1] - pose[1]) < 0.15:
            break
    return poses, cmds


def _touches_lethal(ctl: MppiController, cm: Costmap, poses: list[tuple[float, float, float]]) -> bool:
    fc = cm.footprint_costs(np.array(poses), FOOTPRINT.outline_points(0.025), outside=0)
    return bool((fc == LETHAL).any())


def _controller(seed: int = 0) -> MppiController:
    return MppiController(ControllerConfig(footprint=FOOTPRINT), MppiConfig(seed=seed))


def test_follows_a_straight_path_to_the_goal() -> None:
    cm = _costmap([])
    ctl = _controller()
    path = np.column_stack([np.linspace(1.0, 7.0, 121), np.full(121, 3.0)])
    ctl.set_path(path)
    poses, _ = _drive(ctl, cm, (1.0, 3.0, 0.0), (7.0, 3.0, 0.0))
    end = poses[-1]
    assert math.hypot(end[0] - 7.0, end[1] - 3.0) < 0.15
    assert max(abs(p[1] - 3.0) for p in poses) < 0.2       # stays on the path
    assert not _touches_lethal(ctl, cm, poses)


def test_threads_between_posts_without_contact() -> None:
    # posts 0.95 m apart (centre to centre) straddle the path: 0.80 m clear, wider than the 0.5 m body
    posts = [(3.0, 2.525), (3.0, 3.475), (4.5, 2.6), (4.5, 3.55), (5.5, 2.45)]
    cm = _costmap(posts)
    ctl = _controller()
    path = np.column_stack([np.linspace(1.0, 7.0, 121), np.full(121, 3.0)])
    ctl.set_path(path)
    poses, _ = _drive(ctl, cm, (1.0, 3.0, 0.0), (7.0, 3.0, 0.0), steps=600)
    assert math.hypot(poses[-1][0] - 7.0, poses[-1][1] - 3.0) < 0.15
    assert not _touches_lethal(ctl, cm, poses)


def test_same_seed_same_commands_and_seed_matters() -> None:
    cm = _costmap([(4.0, 3.3)])
    path = np.column_stack([np.linspace(1.0, 7.0, 121), np.full(121, 3.0)])
    runs = []
    for seed in (3, 3, 4):
        ctl = _controller(seed)
        ctl.set_path(path)
        runs.append(_drive(ctl, cm, (1.0, 3.0, 0.0), (7.0, 3.0, 0.0), steps=40)[1])
    assert runs[0] == runs[1]
    assert runs[0] != runs[2]


@pytest.mark.parametrize("limit", [50.0, 20.0])
def test_speed_limit_caps_the_commands(limit: float) -> None:
    cm = _costmap([])
    ctl = _controller()
    ctl.set_speed_limit(limit)
    ctl.set_path(np.column_stack([np.linspace(1.0, 7.0, 121), np.full(121, 3.0)]))
    _, cmds = _drive(ctl, cm, (1.0, 3.0, 0.0), (7.0, 3.0, 0.0), steps=80)
    cap = 0.5 * limit / 100.0
    assert max(math.hypot(c[0], c[1]) for c in cmds) <= math.sqrt(2) * cap + 1e-9


def _doorway_costmap(gap: float) -> tuple[Costmap, np.ndarray]:
    """A wall across x = 4 m with a ``gap`` m opening centred on y = 3 m."""
    grid = np.zeros((120, 160), np.int8)
    grid[0, :] = grid[-1, :] = 100
    grid[:, 0] = grid[:, -1] = 100
    c = int(4.0 / RES)
    grid[:, c:c + 2] = 100
    grid[int((3.0 - gap / 2) / RES):int((3.0 + gap / 2) / RES), c:c + 2] = 0
    cm = Costmap(CostmapConfig(obstacle_layer=False, footprint=FOOTPRINT, inflation_radius=0.55,
                               cost_scaling_factor=3.0))
    cm.set_static_map(GridMap(grid, RES))
    return cm, grid


def _body_clearance(grid: np.ndarray, poses: list[tuple[float, float, float]]) -> float:
    """The footprint outline's smallest distance (m) to an occupied cell over ``poses``, on a 1 cm raster."""
    from scipy.ndimage import distance_transform_edt

    k = 5
    occ = np.kron(grid >= 100, np.ones((k, k), bool))
    dist = distance_transform_edt(~occ) * (RES / k)
    pts = FOOTPRINT.outline_points(0.02)
    p = np.asarray(poses)
    c, s = np.cos(p[:, 2:3]), np.sin(p[:, 2:3])
    px = p[:, 0:1] + c * pts[None, :, 0] - s * pts[None, :, 1]
    py = p[:, 1:2] + s * pts[None, :, 0] + c * pts[None, :, 1]
    col = np.clip((px / (RES / k)).astype(int), 0, dist.shape[1] - 1)
    row = np.clip((py / (RES / k)).astype(int), 0, dist.shape[0] - 1)
    return float(dist[row, col].min())


@pytest.mark.parametrize("start", [(1.5, 1.2, 0.6), (1.5, 4.8, -0.6)])
def test_keeps_body_clearance_entering_a_doorway_at_an_angle(start: tuple[float, float, float]) -> None:
    # a 0.8 m opening entered along a path that bends into it: the centre's cost is the same for a body lined up
    # with the opening and one still turned toward the approach, the corners are not; the clearance critic
    # keeps them off the jambs when switched on. Without it the corner passed within 3.0 and 4.0 cm of a jamb
    # while the passage heading was ranked by summed outline cost and weighted like any heading; ranked by the
    # body's clearance and weighted up (passage_heading_gain), 5.8 and 7.0 cm, and 8.2 and 8.1 cm with the
    # critic: the default must now keep 4 cm too, and the critic must not lose any of it
    from nav2_wrapper.core.planner import densify

    cm, grid = _doorway_costmap(0.8)
    path = densify(np.array([start[:2], (3.4, 3.0), (4.6, 3.0), (7.0, 3.0)]), 0.05)
    clear = {}
    on = 20.0   # the critic is off by default (see MppiController._collisions): this is the weight it was measured at
    for weight in (0.0, on):
        ctl = MppiController(ControllerConfig(footprint=FOOTPRINT), MppiConfig(clearance_weight=weight))
        ctl.set_path(path)
        poses, _ = _drive(ctl, cm, start, (7.0, 3.0, 0.0), steps=600)
        assert math.hypot(poses[-1][0] - 7.0, poses[-1][1] - 3.0) < 0.15
        clear[weight] = _body_clearance(grid, poses)
    assert clear[0.0] >= 0.04
    assert clear[on] >= clear[0.0]
