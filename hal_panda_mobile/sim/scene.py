"""Scenes as data: frozen dataclasses the simulator takes, and the footprint collision checks on them.

A scene is a set of prisms standing on the floor: wall segments (with thickness and height), boxes and
cylinders, plus bounds, a start pose and optional named waypoints (goals for navigation benchmarks).
Walls are extended by half their thickness at each end so that corners close; a doorway's clear width
is therefore the gap between segment end points minus the wall thickness.

Scene files (the built-in YAML worlds, ``from_map``, ``random``) are read by :mod:`hal_panda_mobile.files`,
which validates them against the ranges declared here. Error messages name the field relative to the
object (``size: must be > 0 ...``); the file layer prefixes the path (``boxes[0].size``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from robonix_common.geometry import Pose2D

from .errors import SimConfigError
from .robot import RobotDescription
from .shapes import Circle, Rect, Shape, convex_hull, polygon_distance
from .spec import check_ranges, param

XY = tuple[float, float]


@dataclass(frozen=True)
class Wall:
    start: XY
    end: XY
    thickness: float = param(0.1, gt=0, doc="m")
    height: float = param(2.0, gt=0, doc="m")
    name: str | None = None

    def __post_init__(self) -> None:
        check_ranges(self)
        if math.dist(self.start, self.end) <= 1e-9:
            raise SimConfigError("start and end coincide (zero-length wall)")

    def shape(self) -> Rect:
        (x0, y0), (x1, y1) = self.start, self.end
        length = math.hypot(x1 - x0, y1 - y0)
        return Rect((x0 + x1) / 2, (y0 + y1) / 2, length + self.thickness, self.thickness,
                    math.atan2(y1 - y0, x1 - x0))


@dataclass(frozen=True)
class Box:
    center: XY
    size: XY  # full extents along the box's own x and y
    yaw: float = 0.0
    height: float = param(0.8, gt=0, doc="m")
    name: str | None = None

    def __post_init__(self) -> None:
        check_ranges(self)
        if min(self.size) <= 0:
            raise SimConfigError("size: must be > 0 in both directions")

    def shape(self) -> Rect:
        return Rect(self.center[0], self.center[1], self.size[0], self.size[1], self.yaw)


@dataclass(frozen=True)
class Cylinder:
    center: XY
    radius: float = param(gt=0, doc="m")
    height: float = param(0.8, gt=0, doc="m")
    name: str | None = None

    def __post_init__(self) -> None:
        check_ranges(self)

    def shape(self) -> Circle:
        return Circle(self.center[0], self.center[1], self.radius)


@dataclass(frozen=True)
class Obstacle:
    """A scene prism flattened for the engine: unique name, where it came from, 2-D shape, height."""

    name: str
    ref: str  # e.g. "walls[3]" — the field a user would edit
    shape: Shape
    height: float


@dataclass(frozen=True)
class Scene:
    name: str
    bounds: tuple[float, float, float, float]  # xmin, ymin, xmax, ymax
    start: Pose2D
    description: str = ""
    walls: tuple[Wall, ...] = ()
    boxes: tuple[Box, ...] = ()
    cylinders: tuple[Cylinder, ...] = ()
    waypoints: dict[str, XY] = field(default_factory=dict)

    def __post_init__(self) -> None:
        xmin, ymin, xmax, ymax = self.bounds
        if not (xmax > xmin and ymax > ymin):
            raise SimConfigError("bounds: must be [xmin, ymin, xmax, ymax] with xmax > xmin and ymax > ymin")
        x, y, _ = self.start
        if not (xmin <= x <= xmax and ymin <= y <= ymax):
            raise SimConfigError(f"start ({x}, {y}) lies outside bounds {list(self.bounds)}")
        seen: dict[str, str] = {}
        for ob in self.obstacles():
            if ob.name in seen:
                raise SimConfigError(f"{ob.ref}: name {ob.name!r} already used by {seen[ob.name]}")
            seen[ob.name] = ob.ref

    def obstacles(self) -> list[Obstacle]:
        out: list[Obstacle] = []
        for kind, items, prefix in (("walls", self.walls, "wall"), ("boxes", self.boxes, "box"),
                                    ("cylinders", self.cylinders, "cylinder")):
            for i, item in enumerate(items):
                out.append(Obstacle(item.name or f"{prefix}_{i}", f"{kind}[{i}]", item.shape(), item.height))
        return out


def robot_polygon(robot: RobotDescription, x: float, y: float, yaw: float) -> np.ndarray:
    """World-frame convex footprint at a pose (the bounding box the collision geom covers)."""
    cx, cy, sx, sy = robot.footprint_box
    box = Rect(cx, cy, sx, sy).corners()
    c, s = math.cos(yaw), math.sin(yaw)
    return convex_hull(box @ np.array([[c, s], [-s, c]]) + (x, y))


def first_collision(robot: RobotDescription, obstacles: list[Obstacle], x: float, y: float, yaw: float,
                    clearance: float = 0.0) -> Obstacle | None:
    """The first obstacle closer than ``clearance`` to the footprint at (x, y, yaw), else None."""
    poly = robot_polygon(robot, x, y, yaw)
    px0, py0 = poly.min(axis=0) - clearance
    px1, py1 = poly.max(axis=0) + clearance
    for ob in obstacles:
        ax0, ay0, ax1, ay1 = ob.shape.aabb()
        if ax0 > px1 or ax1 < px0 or ay0 > py1 or ay1 < py0:
            continue
        d = polygon_distance(poly, ob.shape)
        if d <= clearance and (clearance > 0 or d <= 0.0):
            return ob
    return None


def check_start(scene: Scene, robot: RobotDescription) -> None:
    ob = first_collision(robot, scene.obstacles(), *scene.start)
    if ob is not None:
        x, y, yaw = scene.start
        raise SimConfigError(f"scene {scene.name!r}: start: pose ({x:g}, {y:g}, {yaw:g}) collides with "
                             f"{ob.ref} {ob.name!r}")
