"""Shared fixtures for the hal_panda_mobile core tests: the real robot description and small scenes."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hal_panda_mobile.files import load_robot_description, load_scene
from hal_panda_mobile.sim import PandaMobileSim, RobotDescription


@pytest.fixture(scope="session")
def robot() -> RobotDescription:
    return load_robot_description()


def room(half_x: float = 4.0, half_y: float = 3.0, t: float = 0.2, **extra) -> dict:
    """Closed rectangular room centred at the origin; inner faces at +-(half - t/2)."""
    c = [(-half_x, -half_y), (half_x, -half_y), (half_x, half_y), (-half_x, half_y)]
    walls = [{"start": c[i], "end": c[(i + 1) % 4], "thickness": t, "height": 1.0} for i in range(4)]
    scene = {"name": "test_room", "bounds": [-half_x, -half_y, half_x, half_y], "walls": walls,
             "start": [0.0, 0.0, 0.0]}
    scene.update(extra)
    return scene


def make_sim(robot: RobotDescription, scene: dict, **kw) -> PandaMobileSim:
    return PandaMobileSim(robot, load_scene(scene, robot=robot), **kw)


def drive(sim: PandaMobileSim, vx: float, vy: float, wz: float, seconds: float, rate_hz: float = 10.0) -> None:
    """Re-send the command at rate_hz like a navigation stack would (the timeout is 0.5 s)."""
    per = round(1.0 / (rate_hz * sim.timestep))
    for _ in range(round(seconds / sim.timestep) // per):
        sim.set_cmd_vel(vx, vy, wz)
        sim.step(per)


def ray_distances(origin: tuple[float, float], angles: np.ndarray, rects: list[tuple], circles: list[tuple]
                  ) -> np.ndarray:
    """Independent analytic ray cast: rects (cx, cy, sx, sy, yaw) by slabs, circles (cx, cy, r)."""
    ox, oy = origin
    best = np.full(len(angles), np.inf)
    dx, dy = np.cos(angles), np.sin(angles)
    for cx, cy, sx, sy, yaw in rects:
        c, s = math.cos(yaw), math.sin(yaw)
        lox, loy = c * (ox - cx) + s * (oy - cy), -s * (ox - cx) + c * (oy - cy)
        ldx, ldy = c * dx + s * dy, -s * dx + c * dy
        with np.errstate(divide="ignore", invalid="ignore"):
            t1x, t2x = (-sx / 2 - lox) / ldx, (sx / 2 - lox) / ldx
            t1y, t2y = (-sy / 2 - loy) / ldy, (sy / 2 - loy) / ldy
        tmin = np.maximum(np.minimum(t1x, t2x), np.minimum(t1y, t2y))
        tmax = np.minimum(np.maximum(t1x, t2x), np.maximum(t1y, t2y))
        ok = (tmax >= tmin) & (tmin > 0)
        best = np.where(ok, np.minimum(best, tmin), best)
    for cx, cy, r in circles:
        fx, fy = ox - cx, oy - cy
        b = fx * dx + fy * dy
        disc = b * b - (fx * fx + fy * fy - r * r)
        t = -b - np.sqrt(np.maximum(disc, 0))
        best = np.where((disc >= 0) & (t > 0), np.minimum(best, t), best)
    return best
