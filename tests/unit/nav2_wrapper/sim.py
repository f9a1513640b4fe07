"""Test helpers: synthetic maps, a ray-cast lidar on the true grid, and a kinematic integrator loop.

The integrator applies commands exactly (within the base's limits) — no MuJoCo — so the navigation core is
tested alone; collisions are judged on the true grid with the real footprint polygon.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from nav2_wrapper.core import Navigator, Scan
from nav2_wrapper.robot_io import load_footprint
from robonix_common.grid import GridMap

FOOTPRINT = load_footprint()


def room(width_m: float, height_m: float, res: float = 0.05,
         boxes: tuple[tuple[float, float, float, float], ...] = ()) -> GridMap:
    """Free room with 1-cell walls; boxes are (x0, y0, x1, y1) in metres, filled occupied."""
    rows, cols = int(round(height_m / res)), int(round(width_m / res))
    d = np.zeros((rows, cols), dtype=np.int8)
    d[0, :] = d[-1, :] = d[:, 0] = d[:, -1] = 100
    for x0, y0, x1, y1 in boxes:
        d[int(y0 / res):int(math.ceil(y1 / res)), int(x0 / res):int(math.ceil(x1 / res))] = 100
    return GridMap(d, res)


def add_box(grid: GridMap, box: tuple[float, float, float, float]) -> GridMap:
    d = grid.data.copy()
    x0, y0, x1, y1 = box
    r = grid.resolution
    d[int(y0 / r):int(math.ceil(y1 / r)), int(x0 / r):int(math.ceil(x1 / r))] = 100
    return GridMap(d, r, grid.origin_x, grid.origin_y)


def cast_scan(grid: GridMap, pose: tuple[float, float, float], beams: int = 360, rmax: float = 6.0) -> Scan:
    """Ray-cast a 360° scan on the true grid (step res/2; origin yaw assumed 0)."""
    ang = pose[2] + np.linspace(-math.pi, math.pi, beams, endpoint=False)
    t = np.arange(0.05, rmax, grid.resolution / 2)
    x = pose[0] + np.cos(ang)[:, None] * t[None, :]
    y = pose[1] + np.sin(ang)[:, None] * t[None, :]
    c = np.floor((x - grid.origin_x) / grid.resolution).astype(np.int64)
    r = np.floor((y - grid.origin_y) / grid.resolution).astype(np.int64)
    inb = (c >= 0) & (c < grid.width) & (r >= 0) & (r < grid.height)
    hit = np.zeros_like(inb)
    hit[inb] = grid.data[r[inb], c[inb]] >= 50
    hit |= ~inb
    first = np.where(hit.any(axis=1), hit.argmax(axis=1), -1)
    ranges = np.where(first >= 0, t[np.maximum(first, 0)], np.inf)
    return Scan(ranges, -math.pi, 2 * math.pi / beams, 0.05, rmax)


def footprint_collides(grid: GridMap, pose: tuple[float, float, float]) -> bool:
    pts = FOOTPRINT.outline_points(grid.resolution / 2)
    c, s = math.cos(pose[2]), math.sin(pose[2])
    x = pose[0] + c * pts[:, 0] - s * pts[:, 1]
    y = pose[1] + s * pts[:, 0] + c * pts[:, 1]
    cc, rr = grid.world_to_cell(x, y)
    inb = grid.in_bounds(cc, rr)
    return bool(np.any(grid.data[rr[inb], cc[inb]] >= 50) or not inb.all())


@dataclass
class Run:
    poses: list[tuple[float, float, float]] = field(default_factory=list)
    cmds: list = field(default_factory=list)
    collided: bool = False
    t: float = 0.0


def drive(nav: Navigator, grid: GridMap, pose: tuple[float, float, float], t_max: float, dt: float = 0.05,
          t0: float = 0.0, scan: bool = True, world: GridMap | None = None, until_terminal: bool = True,
          on_step=None, scan_fn=None) -> Run:
    """Closed loop: tick the navigator, integrate the body twist, ray-cast scans on ``world`` (default grid).
    ``grid`` is what the navigator is told the map is (sent on the first tick); ``scan_fn(world, pose)``
    replaces the ideal ray cast (e.g. with a noisy one)."""
    world = world or grid
    run = Run()
    x, y, th = pose
    vel = (0.0, 0.0, 0.0)
    t = t0
    first = True
    scan_fn = scan_fn or cast_scan
    while t - t0 < t_max:
        sc = scan_fn(world, (x, y, th)) if scan and int(round(t / dt)) % 2 == 0 else None
        cmd = nav.tick(t, (x, y, th), vel, grid=grid if first else None, scan=sc)
        first = False
        vx = float(np.clip(cmd.vx, -0.5, 0.5))
        vy = float(np.clip(cmd.vy, -0.5, 0.5))
        wz = float(np.clip(cmd.wz, -1.9, 1.9))
        c, s = math.cos(th + wz * dt / 2), math.sin(th + wz * dt / 2)
        x, y, th = x + (c * vx - s * vy) * dt, y + (s * vx + c * vy) * dt, th + wz * dt
        th = (th + math.pi) % (2 * math.pi) - math.pi
        vel = (vx, vy, wz)
        t += dt
        run.poses.append((x, y, th))
        run.cmds.append(cmd)
        if footprint_collides(world, (x, y, th)):
            run.collided = True
        if on_step is not None:
            on_step(t, run)
        if until_terminal and cmd.state in ("SUCCEEDED", "FAILED", "CANCELED"):
            break
    run.t = t
    return run
