"""Reads the robot description YAML (footprint and limits) for navigation.

The navigation core takes a :class:`~nav2_wrapper.core.Footprint` and numbers, never a file: this module is
where the file is read, so the core stays importable and testable without YAML or the data package.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from nav2_wrapper.core.footprint import Footprint
from robonix_api.safefile import UnsafeFileError, read_capped
from robonix_nav_data import resources

ROBOT_YAML = resources.robot_description()
_LIMIT_KEYS = ("max_vx", "max_vy", "max_wz", "max_ax", "max_ay", "max_aw")


class RobotDescriptionError(ValueError):
    """The robot description cannot be used; the message names the file and the key."""


@dataclass(frozen=True)
class RobotLimits:
    """The base's velocity (m/s, rad/s) and acceleration (m/s^2, rad/s^2) limits from ``limits:``."""

    max_vx: float
    max_vy: float
    max_wz: float
    max_ax: float
    max_ay: float
    max_aw: float


@dataclass(frozen=True)
class NavRobot:
    """What navigation takes from the robot description (hal_panda_mobile.sim reads the whole of it)."""

    footprint: Footprint
    limits: RobotLimits | None = None      # None: the description has no ``limits:`` section


#: A robot description is a few hundred bytes.
ROBOT_MAX_BYTES = 256 * 1024

def load_robot(path: str | Path = ROBOT_YAML) -> NavRobot:
    """Footprint and limits from a robot description; RobotDescriptionError names what is wrong."""
    path = Path(path)
    try:  # a regular file of bounded size, checked before reading (a Driver call may name /dev/zero)
        desc = yaml.safe_load(read_capped(path, ROBOT_MAX_BYTES, str(path)))
    except (UnsafeFileError, yaml.YAMLError) as exc:
        raise RobotDescriptionError(f"{path}: cannot read: {exc}") from exc
    if not isinstance(desc, dict) or "footprint" not in desc:
        raise RobotDescriptionError(f"{path}: footprint: missing")
    try:
        footprint = Footprint(np.asarray(desc["footprint"], dtype=float))
    except (TypeError, ValueError) as exc:
        raise RobotDescriptionError(f"{path}: footprint: {exc}") from exc
    raw = desc.get("limits")
    if raw is None:
        return NavRobot(footprint)
    if not isinstance(raw, dict):
        raise RobotDescriptionError(f"{path}: limits: must be a mapping")
    values = {}
    for key in _LIMIT_KEYS:
        v = raw.get(key)
        if isinstance(v, bool) or not isinstance(v, (int, float)) or v <= 0:
            raise RobotDescriptionError(f"{path}: limits.{key}: must be a positive number, got {v!r}")
        values[key] = float(v)
    return NavRobot(footprint, RobotLimits(**values))


def load_footprint(path: str | Path = ROBOT_YAML) -> Footprint:
    """The footprint polygon of a robot description (the single source of the footprint)."""
    return load_robot(path).footprint
