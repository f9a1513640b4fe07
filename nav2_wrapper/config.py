"""The CMD_INIT config of the navigation provider (robonix nav2_wrapper_rbnx keys plus ours).

Validated with pydantic so that every error names the field at fault (``dynamic_speed.min_percentage:
...``); unknown keys are errors too, because a misspelt key silently ignored is a deploy bug.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from robonix_api.config_types import FrameName, OptionalTopicName
from robonix_api.safefile import UnsafeFileError, read_capped
from robonix_api.validation import Seconds, field_errors, per_role
from robonix_nav_data import resources

PKG_ROOT = resources.data_root()  # the repository root (installed: robonix_nav_data): config/ lives here


class ConfigError(ValueError):
    """The config dict is unusable; the message starts with the field path."""


class _M(BaseModel):
    model_config = ConfigDict(extra="forbid")


#: ``scan_cloud`` is robonix's key: accepted, but there is no 3-D source in this core (warned).
TopicRemap = per_role("TopicRemap", ("map", "odom", "scan", "scan_cloud"), OptionalTopicName,
                      doc="Per-role topic overrides (a remapped role is not looked up on the atlas).")
ProviderIds = per_role("ProviderIds", ("map", "odom", "scan", "twist_in"),
                       doc="Pin the atlas provider per role (when several offer the same contract).")


class DynamicSpeed(_M):
    max_linear_speed_mps: float | None = Field(None, gt=0)  # None: the controller's max_vel_x
    default_percentage: float = Field(100.0, gt=0, le=100)
    step_percentage: float = Field(10.0, gt=0, le=100)
    min_percentage: float = Field(10.0, gt=0, le=100)

    @model_validator(mode="after")
    def _order(self) -> DynamicSpeed:
        if self.min_percentage > self.default_percentage:
            raise ValueError(f"min_percentage ({self.min_percentage:g}) must not exceed default_percentage "
                             f"({self.default_percentage:g})")
        return self


class Frames(_M):
    map: FrameName = "map"
    odom: FrameName = "odom"
    base: FrameName = "base_link"


class ProviderConfig(_M):
    params_profile: Literal["sim", "slam", "default"] = "sim"
    params_file: str = ""               # absolute or package-relative; overrides params_profile
    use_sim_time: bool = True
    action_wait_s: Seconds = Field(90.0, gt=0)   # how long CMD_INIT waits for the first map + odom + TF
    topic_remap: TopicRemap = TopicRemap()  # type: ignore[valid-type]
    provider_ids: ProviderIds = ProviderIds()  # type: ignore[valid-type]
    velocity_output_topic: OptionalTopicName = ""     # empty: chassis twist_in from the atlas, else /cmd_vel
    dynamic_speed: DynamicSpeed = DynamicSpeed()
    robot_description: str = "config/panda_mobile.yaml"
    frames: Frames = Frames()
    data_timeout_s: Seconds = Field(1.0, gt=0)   # sim s without odom / fresh odom→base TF before a run fails
    # map→odom is a slowly varying SLAM correction, republished on the SLAM provider's clock: at high
    # real-time factors it can lag by seconds of sim time without being wrong, so it has its own limit.
    map_tf_timeout_s: Seconds = Field(10.0, gt=0)
    clock_stall_s: Seconds = Field(0.5, gt=0)    # wall s without /clock advancing before the robot is stopped
    clock_timeout_s: Seconds = Field(10.0, gt=0)  # wall s of a stalled /clock before a run fails

    def resolve_path(self, value: str) -> Path:
        """Absolute as given; relative to the package root otherwise (robonix convention)."""
        p = Path(value).expanduser()
        return p if p.is_absolute() else PKG_ROOT / p

    @property
    def params_source(self) -> str | Path:
        return self.resolve_path(self.params_file) if self.params_file.strip() else self.params_profile

    def params_text(self) -> str | None:
        """The params file's text, read safely (a regular file under :func:`params_roots`, at most
        :data:`PARAMS_MAX_BYTES`, size checked before reading); None for a built-in profile.
        UnsafeFileError names ``params_file``."""
        if not self.params_file.strip():
            return None
        raw = read_capped(self.resolve_path(self.params_file), PARAMS_MAX_BYTES, "params_file", params_roots())
        try:
            return raw.decode("utf-8")
        except UnicodeDecodeError:
            raise UnsafeFileError(f"params_file: {self.params_file[:200]} is not UTF-8 text") from None


#: A Nav2 params YAML is a few kB; this leaves room for heavily commented files.
PARAMS_MAX_BYTES = 1 << 20
PARAMS_ROOTS_ENV = "ROBONIX_PARAMS_ROOTS"


def params_roots() -> list[Path]:
    """Where ``params_file`` may live: the package root, plus the folders of ``$ROBONIX_PARAMS_ROOTS``
    (``os.pathsep``-separated), so a Driver call cannot make the provider read any file of the machine."""
    extra = [Path(p).expanduser() for p in os.environ.get(PARAMS_ROOTS_ENV, "").split(os.pathsep) if p.strip()]
    return [PKG_ROOT, *extra]


def parse_config(cfg: dict[str, Any] | None) -> ProviderConfig:
    """Validate the CMD_INIT dict; ConfigError lists each bad field as ``path: message``."""
    try:
        return ProviderConfig.model_validate(cfg or {})
    except ValidationError as exc:
        raise ConfigError(field_errors(exc, unknown_key="unknown key (misspelt?)")) from None
