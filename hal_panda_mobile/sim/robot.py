"""Robot description as plain frozen dataclasses: what the simulator needs of config/panda_mobile.yaml.

Reading the YAML is :func:`hal_panda_mobile.files.load_robot_description`; ranges and defaults are declared
here once (see :mod:`.spec`) and checked both when the file is validated and when Python builds one.
Error messages name the field relative to the object (``beams: must be > 0``); the file layer prefixes
the path (``lidar.beams``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

from .errors import SimConfigError
from .spec import check_ranges, param

XY = tuple[float, float]


@dataclass(frozen=True)
class BodySpec:
    height: float = param(0.3, gt=0, doc="m, base box height")
    mass: float = param(40.0, gt=0, doc="kg")

    def __post_init__(self) -> None:
        check_ranges(self)


@dataclass(frozen=True)
class KinematicsSpec:
    type: Literal["holonomic"] = "holonomic"


@dataclass(frozen=True)
class LimitsSpec:
    max_vx: float = param(gt=0, doc="m/s")
    max_vy: float = param(gt=0, doc="m/s")
    max_wz: float = param(gt=0, doc="rad/s")
    max_ax: float = param(gt=0, doc="m/s^2")
    max_ay: float = param(gt=0, doc="m/s^2")
    max_aw: float = param(gt=0, doc="rad/s^2")

    def __post_init__(self) -> None:
        check_ranges(self)


@dataclass(frozen=True)
class LidarSpec:
    frame: str = "laser"
    mount: tuple[float, float, float, float] = (0.0, 0.0, 0.35, 0.0)  # x, y, z, yaw in base_link
    beams: int = param(360, gt=0, doc="beams per sweep")
    fov: float = param(2 * math.pi, gt=0, le=2 * math.pi + 1e-9, doc="rad, field of view")
    range_min: float = param(0.05, ge=0, doc="m")
    range_max: float = param(12.0, gt=0, doc="m")
    rate_hz: float = param(10.0, gt=0, doc="sim-time Hz")
    noise_std: float = param(0.0, ge=0, doc="m, Gaussian on valid returns")
    dropout_prob: float = param(0.0, ge=0, le=1, doc="per beam, reported as +inf")

    def __post_init__(self) -> None:
        check_ranges(self)
        if self.range_max <= self.range_min:
            raise SimConfigError(f"range_max ({self.range_max}) must be > range_min ({self.range_min})")


@dataclass(frozen=True)
class RobotDescription:
    footprint: tuple[XY, ...]
    limits: LimitsSpec
    name: str = "panda_mobile"
    base_frame: str = "base_link"
    odom_frame: str = "odom"
    body: BodySpec = field(default_factory=BodySpec)
    kinematics: KinematicsSpec = field(default_factory=KinematicsSpec)
    cmd_vel_timeout: float = param(0.5, gt=0, doc="s of sim time a cmd_vel is held")
    lidar: LidarSpec = field(default_factory=LidarSpec)

    def __post_init__(self) -> None:
        check_ranges(self)
        v = self.footprint
        if len(v) < 3:
            raise SimConfigError("footprint: needs at least 3 vertices")
        xs, ys = [p[0] for p in v], [p[1] for p in v]
        if max(xs) - min(xs) <= 0 or max(ys) - min(ys) <= 0:
            raise SimConfigError("footprint: polygon has zero area")

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
