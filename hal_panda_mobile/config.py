"""The CMD_INIT config of the provider, validated so every error names the field at fault.

Two stages: ``HalConfig`` checks shapes and numbers (pydantic), then ``build_sim`` resolves the scene,
start pose and robot description into a ready ``PandaMobileSim``. Both raise ``SimConfigError`` whose
message starts with the field path, e.g. ``rates.scan_rate_hz: must be > 0``.
"""

from __future__ import annotations

import dataclasses
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from hal_panda_mobile.files import (
    available_scenes,
    core_field,
    format_validation_error,
    load_robot_description,
    load_scene,
)
from hal_panda_mobile.sim import LidarNoise, OdomNoise, PandaMobileSim, RobotDescription, SimConfigError, SimParams
from robonix_api.config_types import FiniteFloat, TopicName
from robonix_api.validation import finite

#: Faster than this the sim cannot keep up anyway; a huge factor only starves the machine.
MAX_REAL_TIME_FACTOR = 100.0
RealTimeFactor = finite("must be a finite number >= 0 (0 = as fast as possible)")


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class StartPose(_Model):
    x: FiniteFloat
    y: FiniteFloat
    yaw: FiniteFloat = 0.0


class Rates(_Model):
    """Publishing rates in sim-time Hz; scan None means "from the robot description" (10 Hz)."""

    physics_rate_hz: float = Field(500.0, ge=500.0, le=10000.0)  # the core steps at >= 500 Hz
    odom_rate_hz: float = core_field(SimParams, "odom_rate_hz")
    scan_rate_hz: float | None = Field(None, gt=0, le=100.0)
    clock_rate_hz: float = Field(100.0, gt=0, le=1000.0)
    ground_truth_rate_hz: float = Field(10.0, gt=0, le=1000.0)  # evaluation stream; the RPC gives any instant
    hold_rate_hz: float = Field(1.0, gt=0, le=100.0)  # wall-clock Hz of republishing while not ACTIVE


class Topics(_Model):
    odom: TopicName = "/odom"
    cmd_vel: TopicName = "/cmd_vel"
    scan: TopicName = "/scan"
    ground_truth: TopicName = "/ground_truth/odom"


class Frames(_Model):
    """None: taken from the robot description (odom_frame, base_frame, lidar.frame)."""

    odom: str | None = None
    base_link: str | None = None
    laser: str | None = None
    world: str = "world"  # frame of the ground-truth odometry


class HalConfig(_Model):
    scene: Annotated[str, Field(max_length=4096)] | dict[str, Any] = "apartment"
    start: StartPose | None = None
    seed: int = core_field(SimParams, "seed")
    robot: str | None = Field(None, max_length=4096)  # robot description YAML; default config/panda_mobile.yaml
    odom_noise: OdomNoise = OdomNoise()  # also "none" or "realistic" (OdomNoise.realistic())
    lidar_noise: LidarNoise | None = None  # None: the robot description's noise_std/dropout_prob
    rates: Rates = Rates()
    real_time_factor: RealTimeFactor = Field(1.0, ge=0, le=MAX_REAL_TIME_FACTOR)  # 0: as fast as possible
    # sim s the loop may run past the last non-zero /cmd_vel before it waits for the next (0: never waits);
    # keeps a slow controller tick from becoming a long blind drive at rtf > 1 (see hal_panda_mobile.loop)
    command_lag_bound_s: float = Field(0.15, ge=0, le=5.0)
    topics: Topics = Topics()
    frames: Frames = Frames()
    use_sim_time: bool = True
    publish_clock: bool = True
    publish_ground_truth: bool = True
    odom_frame_at_start: bool = core_field(SimParams, "odom_frame_at_start")
    # who may drive the base over /cmd_vel: "deployment" = only writers whose DDS participant carries the
    # deployment's tag (robonix_api.dds.writer_trust; needs ROBONIX_DEPLOY_TOKEN), "any" = every writer on
    # the domain (plain ROS 2 interop), "auto" = "deployment" when a deployment token is set, else "any"
    cmd_vel_writers: Literal["auto", "deployment", "any"] = "auto"

    @field_validator("odom_noise", mode="before")
    @classmethod
    def _noise_kind(cls, v: Any) -> Any:
        if isinstance(v, str):
            if v not in ("realistic", "none"):
                raise ValueError(f"must be 'none', 'realistic' or a mapping of noise fields, got {v!r}")
            return OdomNoise.realistic() if v == "realistic" else OdomNoise()
        return v

    def noise(self) -> OdomNoise:
        return self.odom_noise


def parse_config(cfg: dict[str, Any]) -> HalConfig:
    """Validate the CMD_INIT dict; SimConfigError lists every bad field."""
    try:
        return HalConfig.model_validate(cfg)
    except ValidationError as exc:
        raise SimConfigError(format_validation_error(exc)) from None


def _scene(cfg: HalConfig, robot: RobotDescription) -> Any:
    spec = cfg.scene
    if isinstance(spec, str) and not spec.strip():
        raise SimConfigError(f"scene: must not be empty (available: {', '.join(available_scenes())})")
    if isinstance(spec, dict) and not spec:
        raise SimConfigError("scene: empty mapping; expected a scene, {from_map: <map.yaml>} or {random: {seed}}")
    start = cfg.start.model_dump() if cfg.start is not None else None
    try:
        return load_scene(spec, start=start, robot=robot)
    except SimConfigError as exc:
        msg = str(exc)
        raise SimConfigError(msg if msg.startswith(("scene", "start")) else f"scene: {msg}") from None
    except (TypeError, ValueError, KeyError) as exc:  # e.g. {random: {seed: 1, bogus: 2}}
        raise SimConfigError(f"scene: malformed scene spec: {exc}") from None


def build_sim(cfg: HalConfig) -> PandaMobileSim:
    """The simulator for a validated config (scene, start, noise, rates); SimConfigError names the field."""
    robot = load_robot_description(cfg.robot)
    if cfg.rates.scan_rate_hz is not None:
        robot = dataclasses.replace(robot, lidar=dataclasses.replace(robot.lidar, rate_hz=cfg.rates.scan_rate_hz))
    scene = _scene(cfg, robot)
    return PandaMobileSim(robot, scene, seed=cfg.seed, odom_noise=cfg.noise(), lidar_noise=cfg.lidar_noise,
                          timestep=1.0 / cfg.rates.physics_rate_hz, odom_rate_hz=cfg.rates.odom_rate_hz,
                          odom_frame_at_start=cfg.odom_frame_at_start)
