"""File formats and config validation for the simulator: robot description YAML, scene YAML, map_server maps.

The simulator core (:mod:`hal_panda_mobile.sim`) takes plain dataclasses and reads no file; this package
turns YAML (and CMD_INIT dicts) into them, validated against the ranges the dataclasses declare, with
errors that name the field (``walls[3].thickness: must be > 0``).
"""

from .robot import DEFAULT_ROBOT_YAML, load_robot_description, robot_from_dict
from .scene import SCENES_DIR, available_scenes, load_scene, scene_from_dict, scene_from_map
from .validate import core_field, format_validation_error, validate

__all__ = [
    "DEFAULT_ROBOT_YAML", "SCENES_DIR", "available_scenes", "core_field", "format_validation_error",
    "load_robot_description",
    "load_scene", "robot_from_dict", "scene_from_dict", "scene_from_map", "validate",
]
