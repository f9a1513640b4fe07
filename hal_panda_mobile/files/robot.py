"""Robot description file (config/panda_mobile.yaml) -> :class:`hal_panda_mobile.sim.RobotDescription`.

The YAML is shared with navigation and SLAM, which may add keys of their own: unknown keys are
ignored here rather than rejected, but every key the simulator uses is checked and named on error.
"""

from __future__ import annotations

from pathlib import Path

import yaml

from hal_panda_mobile.sim import RobotDescription, SimConfigError
from robonix_nav_data import resources

from .validate import validate

DEFAULT_ROBOT_YAML = resources.robot_description()


def robot_from_dict(data: object, source: str = "robot description") -> RobotDescription:
    return validate(RobotDescription, data, source, extra="ignore")


def load_robot_description(path: str | Path | None = None) -> RobotDescription:
    """Read config/panda_mobile.yaml (or another file of the same shape)."""
    path = Path(path) if path is not None else DEFAULT_ROBOT_YAML
    try:
        data = yaml.safe_load(path.read_text())
    except (OSError, yaml.YAMLError) as exc:
        raise SimConfigError(f"{path}: cannot read robot description: {exc}") from exc
    return robot_from_dict(data, source=str(path))
