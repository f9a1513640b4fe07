"""Generated scenes: an occupancy grid extruded into boxes (``from_map``) and seeded ``random`` rooms.

Pure: the grid comes in as a :class:`GridMap` (reading the map_server files is
:func:`hal_panda_mobile.files.scene_from_map`), and the robot whose footprint must fit is passed in.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from robonix_common.geometry import Pose2D
from robonix_common.grid import GridMap, merge_cells

from .errors import SimConfigError
from .raster import rasterize, reachable
from .robot import RobotDescription
from .scene import Box, Cylinder, Scene, Wall, first_collision

ROBOT_CLEAR_RADIUS = 0.3  # half the robot width + margin: what a doorway must leave free
MIN_ROOMS = 2  # a generated layout needs somewhere to go: the waypoints are the room centres, one is the start
MAX_LAYOUT_DRAWS = 32  # re-draws of the room grid per seed; P(one room) is 1/6, so 32 misses never happen


def _free_start(grid: GridMap, free: np.ndarray) -> tuple[float, float]:
    """The free cell farthest from any non-free cell: a start pose that is free by construction."""
    if not free.any():
        raise SimConfigError("from_map: the map has no free cell to start in")
    from scipy import ndimage  # here, not at the top: keeps scipy out of the HAL's start-up

    dist = ndimage.distance_transform_edt(np.pad(free, 1))[1:-1, 1:-1]
    r, c = np.unravel_index(int(np.argmax(dist)), dist.shape)
    x, y = grid.cell_to_world(c, r)
    return float(x), float(y)


def scene_from_grid(grid: GridMap, *, name: str, start: Pose2D | None = None, wall_height: float = 1.0,
                    occupied_threshold: int = 65, unknown_occupied: bool = False, description: str = "") -> Scene:
    """Extrude an occupancy grid: occupied cells (>= threshold) become boxes of ``wall_height``."""
    if not wall_height > 0:
        raise SimConfigError(f"from_map: wall_height: must be > 0, got {wall_height}")
    occ = grid.data >= occupied_threshold
    if unknown_occupied:
        occ |= grid.data < 0
    res, c, s = grid.resolution, math.cos(grid.origin_yaw), math.sin(grid.origin_yaw)
    boxes = []
    for r0, r1, c0, c1 in merge_cells(occ):
        lx, ly = (c0 + c1) / 2 * res, (r0 + r1) / 2 * res
        boxes.append(Box(center=(grid.origin_x + c * lx - s * ly, grid.origin_y + s * lx + c * ly),
                         size=((c1 - c0) * res, (r1 - r0) * res), yaw=grid.origin_yaw, height=wall_height,
                         name=f"map_{len(boxes)}"))
    corners = np.array([[0, 0], [grid.width, 0], [0, grid.height], [grid.width, grid.height]]) * res
    wx = grid.origin_x + c * corners[:, 0] - s * corners[:, 1]
    wy = grid.origin_y + s * corners[:, 0] + c * corners[:, 1]
    if start is None:
        free = (grid.data >= 0) & (grid.data < occupied_threshold) & ~occ
        start = (*_free_start(grid, free), 0.0)
    bounds = (float(wx.min()), float(wy.min()), float(wx.max()), float(wy.max()))
    return Scene(name=name, bounds=bounds, boxes=tuple(boxes), start=start, description=description)


def _walls_with_doors(a: float, b: float, fixed: float, vertical: bool, door: float,
                      rng: np.random.Generator) -> tuple[list[Wall], tuple[float, float]]:
    """A wall from a to b along one axis at ``fixed``, with one doorway gap of ``door`` at a random place."""
    a, b = float(a), float(b)
    lo = a + 0.4 + door / 2
    hi = b - 0.4 - door / 2
    mid = float(rng.uniform(lo, hi)) if hi > lo else (a + b) / 2
    segs = [(a, mid - door / 2), (mid + door / 2, b)]
    out = []
    for p, q in segs:
        if q - p > 1e-6:
            out.append(Wall(start=(fixed, p) if vertical else (p, fixed), end=(fixed, q) if vertical else (q, fixed),
                            thickness=0.1, height=2.0))
    return out, ((fixed, mid) if vertical else (mid, fixed))


def _usable_room_grid(seed: int) -> tuple[np.random.Generator, tuple[float, float, np.ndarray, np.ndarray]]:
    """The room grid for ``seed`` with at least MIN_ROOMS rooms, and the generator to draw the rest from.

    Why: the waypoints are the room centres and the robot starts at one of them, so a one-room layout has
    nothing to drive to (``rbnx demo`` would have to refuse it). The first draw uses ``default_rng(seed)``
    exactly as before, so every seed that already had two rooms keeps its world; a one-room draw is
    replaced by a draw from ``default_rng([seed, k])`` for k = 1, 2, ... until one qualifies. Deterministic:
    the same seed still always gives the same world."""
    for k in range(MAX_LAYOUT_DRAWS):
        rng = np.random.default_rng(seed if k == 0 else [seed, k])
        layout = _room_grid(rng)
        if (len(layout[2]) - 1) * (len(layout[3]) - 1) >= MIN_ROOMS:
            return rng, layout
    raise SimConfigError(f"random:{seed}: no layout with {MIN_ROOMS} rooms in {MAX_LAYOUT_DRAWS} draws")


def _room_grid(rng: np.random.Generator) -> tuple[float, float, np.ndarray, np.ndarray]:
    """Outer size (W, H) and the jittered x / y lines that split it into rooms."""
    W, H = float(rng.uniform(8, 16)), float(rng.uniform(8, 14))
    nx, ny = int(rng.integers(1, 4)), int(rng.integers(1, 3))
    xs = np.linspace(0, W, nx + 1)
    ys = np.linspace(0, H, ny + 1)
    xs[1:-1] += rng.uniform(-0.5, 0.5, nx - 1)
    ys[1:-1] += rng.uniform(-0.5, 0.5, ny - 1)
    return W, H, xs, ys


def _room_walls(W: float, H: float, xs: np.ndarray, ys: np.ndarray, rng: np.random.Generator
                ) -> tuple[list[Wall], list[tuple[float, float]]]:
    """The outer walls and every inner wall with its doorway; the doorway centres (kept free of furniture)."""
    walls = [Wall(start=p, end=q, thickness=0.15, height=2.5)
             for p, q in (((0, 0), (W, 0)), ((W, 0), (W, H)), ((W, H), (0, H)), ((0, H), (0, 0)))]
    doors: list[tuple[float, float]] = []
    door = 1.2
    nx, ny = len(xs) - 1, len(ys) - 1
    for i in range(1, nx):
        for j in range(ny):
            segs, d = _walls_with_doors(ys[j], ys[j + 1], float(xs[i]), True, door, rng)
            walls += segs
            doors.append(d)
    for j in range(1, ny):
        for i in range(nx):
            segs, d = _walls_with_doors(xs[i], xs[i + 1], float(ys[j]), False, door, rng)
            walls += segs
            doors.append(d)
    return walls, doors


def _furniture_candidate(k: int, xs: np.ndarray, ys: np.ndarray, keep_clear: list[tuple[float, float]],
                         rng: np.random.Generator) -> Box | Cylinder | None:
    """A random stool or crate inside a random room, or None when it would not fit or blocks a keep-clear spot.
    Draws from ``rng`` in the same order whatever the outcome, so a seed always yields the same world."""
    i, j = int(rng.integers(len(xs) - 1)), int(rng.integers(len(ys) - 1))
    as_cyl = rng.random() < 0.3
    size = rng.uniform(0.3, 1.2, 2)
    cx = float(rng.uniform(xs[i] + 0.2 + size.max() / 2, xs[i + 1] - 0.2 - size.max() / 2)) \
        if xs[i + 1] - xs[i] > size.max() + 0.4 else None
    cy = float(rng.uniform(ys[j] + 0.2 + size.max() / 2, ys[j + 1] - 0.2 - size.max() / 2)) \
        if ys[j + 1] - ys[j] > size.max() + 0.4 else None
    if cx is None or cy is None or any(math.dist((cx, cy), p) < 1.2 + size.max() / 2 for p in keep_clear):
        return None
    if as_cyl:
        return Cylinder(center=(cx, cy), radius=float(size[0] / 2), height=0.8, name=f"stool_{k}")
    return Box(center=(cx, cy), size=(float(size[0]), float(size[1])), yaw=float(rng.uniform(-math.pi, math.pi)),
               height=float(rng.uniform(0.5, 1.5)), name=f"crate_{k}")


def random_scene(robot: RobotDescription, seed: int = 0, *, name: str | None = None,
                 start: Pose2D | None = None) -> Scene:
    """Rooms on a jittered grid (at least MIN_ROOMS, see :func:`_usable_room_grid`), every neighbouring pair
    joined by a 1.2 m doorway, furniture that never blocks a doorway or disconnects a room (for ``robot``'s
    footprint), start at a free room centre. Same seed -> same world."""
    rng, (W, H, xs, ys) = _usable_room_grid(seed)
    walls, doors = _room_walls(W, H, xs, ys, rng)
    nx, ny = len(xs) - 1, len(ys) - 1
    centres = {f"room_{i}_{j}": ((xs[i] + xs[i + 1]) / 2, (ys[j] + ys[j + 1]) / 2)
               for i in range(nx) for j in range(ny)}
    names = list(centres)
    start_room = names[int(rng.integers(len(names)))]
    sx, sy = centres[start_room]
    start_pose = start if start is not None else (float(sx), float(sy), float(rng.uniform(-math.pi, math.pi)))
    scene = Scene(name=name or f"random:{seed}", bounds=(0.0, 0.0, W, H), walls=tuple(walls), start=start_pose,
                  waypoints={k: (float(x), float(y)) for k, (x, y) in centres.items()},
                  description=f"procedural rooms, seed {seed}")
    keep_clear = list(centres.values()) + doors
    wanted = int(rng.integers(2, 4)) * len(names)
    for k in range(8 * len(names)):
        if len(scene.boxes) + len(scene.cylinders) >= wanted:
            break
        item = _furniture_candidate(k, xs, ys, keep_clear, rng)
        if item is None:
            continue
        kind = "cylinders" if isinstance(item, Cylinder) else "boxes"
        trial = dataclasses.replace(scene, **{kind: (*getattr(scene, kind), item)})
        if first_collision(robot, trial.obstacles(), *trial.start, clearance=0.3) is not None:
            continue
        grid = rasterize(trial.obstacles(), trial.bounds, 0.1, inflate=ROBOT_CLEAR_RADIUS)
        if all(reachable(grid, (sx, sy), list(centres.values()))):
            scene = trial
    return scene
