"""Scenes as data: validated models, the built-in YAML worlds, and ``load_scene``.

A scene is a set of prisms standing on the floor: wall segments (with thickness and height), boxes and
cylinders, plus bounds, a start pose and optional named waypoints (goals for navigation benchmarks).
Walls are extended by half their thickness at each end so that corners close; a doorway's clear width
is therefore the gap between segment end points minus the wall thickness.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from robonix_nav_data import resources

from .errors import SimConfigError, config_error
from .robot import RobotDescription, load_robot_description
from .shapes import Circle, Rect, Shape, convex_hull, polygon_distance

SCENES_DIR = resources.scenes_dir()

XY = tuple[float, float]


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid")


class Pose2D(_Model):
    x: float
    y: float
    yaw: float = 0.0

    @model_validator(mode="before")
    @classmethod
    def _from_list(cls, v: Any) -> Any:
        if isinstance(v, list | tuple):
            if len(v) not in (2, 3):
                raise ValueError("pose must be [x, y] or [x, y, yaw]")
            return dict(zip(("x", "y", "yaw"), v, strict=False))
        return v

    def as_tuple(self) -> tuple[float, float, float]:
        return (self.x, self.y, self.yaw)


class Wall(_Model):
    start: XY
    end: XY
    thickness: float = Field(0.1, gt=0)
    height: float = Field(2.0, gt=0)
    name: str | None = None

    @model_validator(mode="after")
    def _length(self) -> Wall:
        if math.dist(self.start, self.end) <= 1e-9:
            raise ValueError("start and end coincide (zero-length wall)")
        return self

    def shape(self) -> Rect:
        (x0, y0), (x1, y1) = self.start, self.end
        length = math.hypot(x1 - x0, y1 - y0)
        return Rect((x0 + x1) / 2, (y0 + y1) / 2, length + self.thickness, self.thickness,
                    math.atan2(y1 - y0, x1 - x0))


class Box(_Model):
    center: XY
    size: XY  # full extents along the box's own x and y
    yaw: float = 0.0
    height: float = Field(0.8, gt=0)
    name: str | None = None

    @field_validator("size")
    @classmethod
    def _positive(cls, v: XY) -> XY:
        if min(v) <= 0:
            raise ValueError("must be > 0 in both directions")
        return v

    def shape(self) -> Rect:
        return Rect(self.center[0], self.center[1], self.size[0], self.size[1], self.yaw)


class Cylinder(_Model):
    center: XY
    radius: float = Field(gt=0)
    height: float = Field(0.8, gt=0)
    name: str | None = None

    def shape(self) -> Circle:
        return Circle(self.center[0], self.center[1], self.radius)


@dataclass(frozen=True)
class Obstacle:
    """A scene prism flattened for the engine: unique name, where it came from, 2-D shape, height."""

    name: str
    ref: str  # e.g. "walls[3]" — the field a user would edit
    shape: Shape
    height: float


class Scene(_Model):
    name: str
    description: str = ""
    bounds: tuple[float, float, float, float]  # xmin, ymin, xmax, ymax
    walls: list[Wall] = []
    boxes: list[Box] = []
    cylinders: list[Cylinder] = []
    start: Pose2D
    waypoints: dict[str, XY] = {}

    @field_validator("bounds")
    @classmethod
    def _bounds(cls, v: tuple[float, float, float, float]) -> tuple[float, float, float, float]:
        if not (v[2] > v[0] and v[3] > v[1]):
            raise ValueError("must be [xmin, ymin, xmax, ymax] with xmax > xmin and ymax > ymin")
        return v

    @model_validator(mode="after")
    def _consistent(self) -> Scene:
        xmin, ymin, xmax, ymax = self.bounds
        if not (xmin <= self.start.x <= xmax and ymin <= self.start.y <= ymax):
            raise ValueError(f"start ({self.start.x}, {self.start.y}) lies outside bounds {list(self.bounds)}")
        seen: dict[str, str] = {}
        for ob in self.obstacles():
            if ob.name in seen:
                raise ValueError(f"{ob.ref}: name {ob.name!r} already used by {seen[ob.name]}")
            seen[ob.name] = ob.ref
        return self

    def obstacles(self) -> list[Obstacle]:
        out: list[Obstacle] = []
        for field, items, prefix in (("walls", self.walls, "wall"), ("boxes", self.boxes, "box"),
                                     ("cylinders", self.cylinders, "cylinder")):
            for i, item in enumerate(items):
                out.append(Obstacle(item.name or f"{prefix}_{i}", f"{field}[{i}]", item.shape(), item.height))
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
    ob = first_collision(robot, scene.obstacles(), *scene.start.as_tuple())
    if ob is not None:
        s = scene.start
        raise SimConfigError(f"scene {scene.name!r}: start: pose ({s.x:g}, {s.y:g}, {s.yaw:g}) collides with "
                             f"{ob.ref} {ob.name!r}")


def available_scenes() -> list[str]:
    """Built-in scene names (files in hal_panda_mobile/scenes/) plus the generated kinds."""
    return sorted([p.stem for p in SCENES_DIR.glob("*.yaml")] + ["random"])


def scene_from_dict(data: object, source: str = "scene") -> Scene:
    if not isinstance(data, dict):
        raise SimConfigError(f"{source}: must be a mapping, got {type(data).__name__}")
    try:
        return Scene.model_validate(data)
    except ValidationError as exc:
        raise config_error(exc, prefix=f"{source}: ") from exc


def _read_yaml(path: Path) -> Any:
    try:
        return yaml.safe_load(path.read_text())
    except OSError as exc:
        raise SimConfigError(f"scene: cannot read {path}: {exc}") from exc
    except yaml.YAMLError as exc:
        raise SimConfigError(f"scene: {path}: malformed YAML: {exc}") from exc


def _from_spec_dict(data: dict, base_dir: Path, source: str) -> Scene:
    from .worldgen import random_scene, scene_from_map

    if "from_map" in data:
        opts = {k: v for k, v in data.items() if k != "from_map"}
        p = Path(str(data["from_map"]))
        return scene_from_map(p if p.is_absolute() else base_dir / p, **opts)
    if "random" in data:
        opts = dict(data["random"] or {}) if isinstance(data["random"], dict) else {"seed": data["random"]}
        extra = {k: v for k, v in data.items() if k != "random"}
        return random_scene(**opts, **extra)
    if set(data) <= {"scene", "start"} and "scene" in data:
        scene = load_scene(data["scene"], check=False)
        return _with_start(scene, data["start"]) if "start" in data else scene
    return scene_from_dict(data, source)


def _with_start(scene: Scene, start: Any) -> Scene:
    try:
        pose = Pose2D.model_validate(start)
    except ValidationError as exc:
        raise config_error(exc, prefix="start: ") from exc
    return scene_from_dict({**scene.model_dump(), "start": pose.model_dump()}, f"scene {scene.name!r}")


def load_scene(spec: str | Path | dict | Scene, *, start: Any = None, robot: RobotDescription | None = None,
               check: bool = True) -> Scene:
    """Scene from a built-in name, ``random`` / ``random:<seed>``, a YAML path (a scene, or a
    map_server map YAML which is extruded like ``from_map``), or a dict.

    Dict forms: a full scene, ``{from_map: <map.yaml>, start?, wall_height?}``, ``{random: {seed: 3}}``,
    or ``{scene: <name>, start: [x, y, yaw]}``. ``start`` overrides the scene's start pose. With
    ``check`` the start pose is tested against the (default) robot footprint.
    """
    if isinstance(spec, Scene):
        scene = spec
    elif isinstance(spec, dict):
        scene = _from_spec_dict(spec, Path.cwd(), "scene")
    elif isinstance(spec, str | Path):
        text = str(spec)
        path = Path(text)
        if text == "random" or text.startswith("random:"):
            from .worldgen import random_scene

            seed_txt = text.partition(":")[2] or "0"
            try:
                seed = int(seed_txt)
            except ValueError as exc:
                raise SimConfigError(f"scene: random seed must be an integer, got {seed_txt!r}") from exc
            scene = random_scene(seed=seed)
        elif path.suffix in (".yaml", ".yml") or path.exists():
            data = _read_yaml(path)
            if not isinstance(data, dict):
                raise SimConfigError(f"scene: {path}: must be a mapping, got {type(data).__name__}")
            if {"image", "resolution", "origin"} <= set(data):  # a map_server map itself
                from .worldgen import scene_from_map

                scene = scene_from_map(path)
            else:
                scene = _from_spec_dict(data, path.parent, str(path))
        elif (SCENES_DIR / f"{text}.yaml").exists():
            scene = _from_spec_dict(_read_yaml(SCENES_DIR / f"{text}.yaml"), SCENES_DIR, f"scene {text!r}")
        else:
            raise SimConfigError(f"scene: unknown scene {text!r}; available: {', '.join(available_scenes())} "
                                 "(or a path to a scene YAML, or {from_map: <map.yaml>})")
    else:
        raise SimConfigError(f"scene: expected a name, path or mapping, got {type(spec).__name__}")
    if start is not None:
        scene = _with_start(scene, start)
    if check:
        check_start(scene, robot or load_robot_description())
    return scene
