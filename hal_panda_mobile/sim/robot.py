"""Robot description (config/panda_mobile.yaml) as a validated model.

The YAML is shared with navigation and SLAM, which may add keys of their own: unknown keys are
ignored here rather than rejected, but every key the simulator uses is checked and named on error.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Literal

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from robonix_nav_data import resources

from .errors import SimConfigError, config_error

DEFAULT_ROBOT_YAML = resources.robot_description()


class _Model(BaseModel):
    model_config = ConfigDict(extra="ignore", frozen=True)


class BodySpec(_Model):
    height: float = Field(0.3, gt=0)
    mass: float = Field(40.0, gt=0)


class KinematicsSpec(_Model):
    type: Literal["holonomic"] = "holonomic"


class LimitsSpec(_Model):
    max_vx: float = Field(gt=0)
    max_vy: float = Field(gt=0)
    max_wz: float = Field(gt=0)
    max_ax: float = Field(gt=0)
    max_ay: float = Field(gt=0)
    max_aw: float = Field(gt=0)


class LidarSpec(_Model):
    frame: str = "laser"
    mount: tuple[float, float, float, float] = (0.0, 0.0, 0.35, 0.0)  # x, y, z, yaw in base_link
    beams: int = Field(360, gt=0)
    fov: float = Field(2 * math.pi, gt=0, le=2 * math.pi + 1e-9)
    range_min: float = Field(0.05, ge=0)
    range_max: float = Field(12.0, gt=0)
    rate_hz: float = Field(10.0, gt=0)
    noise_std: float = Field(0.0, ge=0)
    dropout_prob: float = Field(0.0, ge=0, le=1)

    @model_validator(mode="after")
    def _range_order(self) -> LidarSpec:
        if self.range_max <= self.range_min:
            raise ValueError(f"range_max ({self.range_max}) must be > range_min ({self.range_min})")
        return self


class RobotDescription(_Model):
    name: str = "panda_mobile"
    base_frame: str = "base_link"
    odom_frame: str = "odom"
    footprint: tuple[tuple[float, float], ...]
    body: BodySpec = BodySpec()
    kinematics: KinematicsSpec = KinematicsSpec()
    limits: LimitsSpec
    cmd_vel_timeout: float = Field(0.5, gt=0)
    lidar: LidarSpec = LidarSpec()

    @field_validator("footprint")
    @classmethod
    def _polygon(cls, v: tuple[tuple[float, float], ...]) -> tuple[tuple[float, float], ...]:
        if len(v) < 3:
            raise ValueError("needs at least 3 vertices")
        xs, ys = [p[0] for p in v], [p[1] for p in v]
        if max(xs) - min(xs) <= 0 or max(ys) - min(ys) <= 0:
            raise ValueError("polygon has zero area")
        return v

    @property
    def footprint_box(self) -> tuple[float, float, float, float]:
        """(cx, cy, sx, sy) of the footprint's bounding box: the collision box covers it."""
        xs = [p[0] for p in self.footprint]
        ys = [p[1] for p in self.footprint]
        return ((max(xs) + min(xs)) / 2, (max(ys) + min(ys)) / 2, max(xs) - min(xs), max(ys) - min(ys))

    @property
    def footprint_radius(self) -> float:
        """Circumscribed radius about base_link (what a beam must clear not to see the robot)."""
        return max(math.hypot(x, y) for x, y in self.footprint)


def robot_from_dict(data: object, source: str = "robot description") -> RobotDescription:
    if not isinstance(data, dict):
        raise SimConfigError(f"{source}: must be a mapping, got {type(data).__name__}")
    try:
        return RobotDescription.model_validate(data)
    except ValidationError as exc:
        raise config_error(exc, prefix=f"{source}: ") from exc


def load_robot_description(path: str | Path | None = None) -> RobotDescription:
    """Read config/panda_mobile.yaml (or another file of the same shape)."""
    path = Path(path) if path is not None else DEFAULT_ROBOT_YAML
    try:
        data = yaml.safe_load(path.read_text())
    except (OSError, yaml.YAMLError) as exc:
        raise SimConfigError(f"{path}: cannot read robot description: {exc}") from exc
    return robot_from_dict(data, source=str(path))
