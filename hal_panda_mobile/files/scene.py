"""Scene files -> :class:`hal_panda_mobile.sim.Scene`: built-in names, scene YAML, map_server maps, ``random``.

``load_scene`` accepts a built-in name, ``random`` / ``random:<seed>``, a YAML path (a scene, or a
map_server map YAML which is extruded like ``from_map``), or a dict. Dict forms: a full scene,
``{from_map: <map.yaml>, start?, wall_height?}``, ``{random: {seed: 3}}``, or ``{scene: <name>, start: [x, y, yaw]}``.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import yaml

from hal_panda_mobile.sim import RobotDescription, Scene, SimConfigError, check_start, random_scene, scene_from_grid
from robonix_api.mapfile import MapFileError, load_map_yaml
from robonix_common.geometry import Pose2D
from robonix_nav_data import resources

from .robot import load_robot_description
from .validate import validate

SCENES_DIR = resources.scenes_dir()


def parse_pose(value: Any, field: str = "start") -> Pose2D:
    """``[x, y]``, ``[x, y, yaw]`` or ``{x, y, yaw?}`` -> ``(x, y, yaw)`` (numbers checked when validated)."""
    if isinstance(value, dict):
        unknown = set(value) - {"x", "y", "yaw"}
        if unknown or not {"x", "y"} <= set(value):
            raise SimConfigError(f"{field}: pose must be {{x, y, yaw?}}, got keys {sorted(value)}")
        value = [value["x"], value["y"], value.get("yaw", 0.0)]
    if not isinstance(value, list | tuple) or len(value) not in (2, 3):
        raise SimConfigError(f"{field}: pose must be [x, y] or [x, y, yaw], got {value!r}")
    xyz = [*value, 0.0][:3]
    try:
        return (float(xyz[0]), float(xyz[1]), float(xyz[2]))
    except (TypeError, ValueError):
        raise SimConfigError(f"{field}: pose must be numbers [x, y, yaw], got {list(value)!r}") from None


def available_scenes() -> list[str]:
    """Built-in scene names (files in hal_panda_mobile/scenes/) plus the generated kinds."""
    return sorted([p.stem for p in SCENES_DIR.glob("*.yaml")] + ["random"])


def scene_from_dict(data: object, source: str = "scene") -> Scene:
    if isinstance(data, dict) and "start" in data:
        data = {**data, "start": parse_pose(data["start"], f"{source}: start")}
    return validate(Scene, data, source)


def scene_from_map(path: str | Path, *, start: Any = None, name: str | None = None, **options: Any) -> Scene:
    """Extrude a map_server map (PGM + YAML): occupied cells (>= threshold) become boxes of ``wall_height``."""
    try:
        grid = load_map_yaml(path)
    except MapFileError as exc:
        raise SimConfigError(f"from_map: {exc}") from exc
    pose = parse_pose(start, "from_map: start") if start is not None else None
    return scene_from_grid(grid, name=name or f"from_map:{Path(path).stem}", start=pose,
                           description=f"extruded from {path}", **options)


def _read_yaml(path: Path) -> Any:
    try:
        return yaml.safe_load(path.read_text())
    except OSError as exc:
        raise SimConfigError(f"scene: cannot read {path}: {exc}") from exc
    except yaml.YAMLError as exc:
        raise SimConfigError(f"scene: {path}: malformed YAML: {exc}") from exc


def _random(seed: int, robot: RobotDescription | None, **options: Any) -> Scene:
    if "start" in options and options["start"] is not None:
        options["start"] = parse_pose(options["start"])
    return random_scene(robot or load_robot_description(), seed, **options)


def _from_spec_dict(data: dict, base_dir: Path, source: str, robot: RobotDescription | None) -> Scene:
    if "from_map" in data:
        opts = {k: v for k, v in data.items() if k != "from_map"}
        p = Path(str(data["from_map"]))
        return scene_from_map(p if p.is_absolute() else base_dir / p, **opts)
    if "random" in data:
        opts = dict(data["random"] or {}) if isinstance(data["random"], dict) else {"seed": data["random"]}
        extra = {k: v for k, v in data.items() if k != "random"}
        return _random(robot=robot, **opts, **extra)
    if set(data) <= {"scene", "start"} and "scene" in data:
        scene = load_scene(data["scene"], robot=robot, check=False)
        return with_start(scene, data["start"]) if "start" in data else scene
    return scene_from_dict(data, source)


def with_start(scene: Scene, start: Any) -> Scene:
    """The scene with another start pose (checked against its bounds)."""
    pose = parse_pose(start)
    try:
        return dataclasses.replace(scene, start=pose)
    except SimConfigError as exc:
        raise SimConfigError(f"scene {scene.name!r}: {exc}") from None


def _from_path(text: str, robot: RobotDescription | None) -> Scene:
    path = Path(text)
    if text == "random" or text.startswith("random:"):
        seed_txt = text.partition(":")[2] or "0"
        try:
            seed = int(seed_txt)
        except ValueError as exc:
            raise SimConfigError(f"scene: random seed must be an integer, got {seed_txt!r}") from exc
        return _random(seed, robot)
    if path.suffix in (".yaml", ".yml") or path.exists():
        data = _read_yaml(path)
        if not isinstance(data, dict):
            raise SimConfigError(f"scene: {path}: must be a mapping, got {type(data).__name__}")
        if {"image", "resolution", "origin"} <= set(data):  # a map_server map itself
            return scene_from_map(path)
        return _from_spec_dict(data, path.parent, str(path), robot)
    if (SCENES_DIR / f"{text}.yaml").exists():
        return _from_spec_dict(_read_yaml(SCENES_DIR / f"{text}.yaml"), SCENES_DIR, f"scene {text!r}", robot)
    raise SimConfigError(f"scene: unknown scene {text!r}; available: {', '.join(available_scenes())} "
                         "(or a path to a scene YAML, or {from_map: <map.yaml>})")


def load_scene(spec: str | Path | dict | Scene, *, start: Any = None, robot: RobotDescription | None = None,
               check: bool = True) -> Scene:
    """Scene from a name, path or dict (see the module doc); ``start`` overrides the scene's start pose.
    With ``check`` the start pose is tested against ``robot``'s footprint (default: the repo's robot)."""
    if isinstance(spec, Scene):
        scene = spec
    elif isinstance(spec, dict):
        scene = _from_spec_dict(spec, Path.cwd(), "scene", robot)
    elif isinstance(spec, str | Path):
        scene = _from_path(str(spec), robot)
    else:
        raise SimConfigError(f"scene: expected a name, path or mapping, got {type(spec).__name__}")
    if start is not None:
        scene = with_start(scene, start)
    if check:
        check_start(scene, robot or load_robot_description())
    return scene
