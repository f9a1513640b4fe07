"""The heading the controller holds through a doorway (``HolonomicController._passage_yaw``).

A 0.70 × 0.50 m body in a 1.1 m doorway has 0.3 m to each jamb lined up with the crossing and 0.2 m crossing
sideways; off the door's centre line or along a path that meets the wall at an angle, a skewed or sideways body
comes much closer. The demo once touched a jamb crossing sideways 16 cm off the centre line, with the heading
chosen by the summed outline cost; these cases check the chosen heading by the body's true clearance instead.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.ndimage import distance_transform_edt

from nav2_wrapper.core.controller import ControllerConfig, HolonomicController
from nav2_wrapper.core.costmap import Costmap, CostmapConfig
from nav2_wrapper.core.footprint import Footprint
from nav2_wrapper.core.planner import densify
from robonix_common.grid import GridMap

RES = 0.05
FOOTPRINT = Footprint(np.array([[0.35, 0.25], [-0.35, 0.25], [-0.35, -0.25], [0.35, -0.25]]))
DOOR_X, WALL_Y, DOOR = 3.0, 3.0, 1.1      # a 0.1 m wall along y = 3.0 .. 3.1 m, door x = 2.45 .. 3.55 m
CROSSING = math.pi / 2                    # the direction straight through the door


def _door() -> tuple[Costmap, np.ndarray]:
    grid = np.zeros((120, 120), np.int8)
    r = int(round(WALL_Y / RES))
    grid[r:r + 2, :] = 100
    grid[r:r + 2, int(round((DOOR_X - DOOR / 2) / RES)):int(round((DOOR_X + DOOR / 2) / RES))] = 0
    # the robot profile's inflation (config/nav2_params_*.yml)
    cm = Costmap(CostmapConfig(obstacle_layer=False, footprint=FOOTPRINT, inflation_radius=0.55,
                               cost_scaling_factor=3.0))
    cm.set_static_map(GridMap(grid, RES))
    return cm, grid


def _clearance(grid: np.ndarray, x: float, y: float, yaw: float) -> float:
    """The outline's smallest distance (m) to an occupied cell, on a 1 cm raster of the true grid."""
    k = 5
    dist = distance_transform_edt(~np.kron(grid >= 100, np.ones((k, k), bool))) * (RES / k)
    pts = FOOTPRINT.outline_points(0.01)
    c, s = math.cos(yaw), math.sin(yaw)
    col = ((x + c * pts[:, 0] - s * pts[:, 1]) / (RES / k)).astype(int)
    row = ((y + s * pts[:, 0] + c * pts[:, 1]) / (RES / k)).astype(int)
    return float(dist[row, col].min())


def _off_crossing(yaw: float) -> float:
    """Degrees between the body's long axis (either end leading) and the crossing direction."""
    return abs((math.degrees(yaw - CROSSING) + 90.0) % 180.0 - 90.0)


@pytest.mark.parametrize(("offset", "angle"), [(0.08, -40), (0.08, 40), (-0.08, -10), (0.08, 10), (0.0, 0)])
def test_a_doorway_is_crossed_lined_up_with_the_most_room(offset: float, angle: float) -> None:
    # a straight path through the wall ``offset`` m off the door's centre line, ``angle`` degrees off square; the
    # robot 0.6 m before the wall, so the tightest point ahead is in or just before the doorway
    heading = CROSSING - math.radians(angle)
    cx, cy = DOOR_X + offset, WALL_Y + 0.05
    d = np.array([math.cos(heading), math.sin(heading)])
    path = densify(np.array([(cx, cy) - 2.0 * d, (cx, cy) + 2.0 * d]), 0.05)
    cm, grid = _door()
    ctl = HolonomicController(ControllerConfig(footprint=FOOTPRINT))
    ctl.set_path(path)
    i = len(path) // 2 - 12
    yaw = ctl._passage_yaw(i, heading, cm)
    assert yaw is not None, "a 1.1 m doorway is a narrow passage for this body"
    # where it was judged: the tightest path point ahead (highest centre cost), as the controller does
    ahead = path[i:int(np.searchsorted(ctl.path_cum, ctl.path_cum[i] + ctl.cfg.passage_lookahead)) + 1]
    x, y = ahead[int(np.argmax(cm.cost_at(ahead[:, 0], ahead[:, 1], outside=0)))]
    chosen = _clearance(grid, x, y, yaw)
    best = max(_clearance(grid, x, y, CROSSING + math.radians(a)) for a in range(0, 180, 5))
    sideways = _clearance(grid, x, y, CROSSING + math.pi / 2)
    assert _off_crossing(yaw) <= 30.0 + 1e-6, math.degrees(yaw)
    assert chosen > sideways + 0.03, (chosen, sideways)
    assert chosen >= best - RES, (math.degrees(yaw), chosen, best)   # the most room, to within a cell


def test_mppi_weights_the_heading_up_only_for_the_passage_yaw() -> None:
    from nav2_wrapper.core.mppi import MppiConfig, MppiController

    cm, _ = _door()
    path = densify(np.array([(DOOR_X, 1.0), (DOOR_X, 5.0)]), 0.05)
    ctl = MppiController(ControllerConfig(footprint=FOOTPRINT), MppiConfig(passage_heading_gain=4.0))
    ctl.set_path(path)
    goal = (DOOR_X, 5.0, 0.0)
    # 0.6 m before the wall: the door is ahead, the target is the passage yaw (lined up with the crossing)
    target, gain = ctl._heading_target_and_gain(len(path) // 2 - 12, (DOOR_X, 2.45, 0.0), goal, cm)
    assert gain == 4.0
    assert _off_crossing(target) < 1.0
    # 1.5 m past it, in open space: the path direction at the base weight
    target, gain = ctl._heading_target_and_gain(len(path) - 10, (DOOR_X, 4.55, 0.0), goal, cm)
    assert gain == 1.0
    # with the planner's headings the planned yaw rules, at the base weight
    ctl.set_path(path, np.full(len(path), 0.3))
    target, gain = ctl._heading_target_and_gain(len(path) // 2 - 12, (DOOR_X, 2.45, 0.0), goal, cm)
    assert (target, gain) == (pytest.approx(0.3), 1.0)
