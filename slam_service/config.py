"""The provider's CMD_INIT config, validated so every error names the field at fault.

pydantic checks shapes and numbers (``extra="forbid"``: a typo is an error, not a silently ignored
key); the ``slam`` block goes to :meth:`SlamConfig.from_dict`, which names unknown or bad keys itself
against the ranges declared on its fields.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any, Literal

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from robonix_api.config_types import FiniteFloat, FrameName, OptionalTopicName
from robonix_api.validation import Seconds, field_errors, per_role
from robonix_common.params import ParamError
from robonix_nav_data import resources
from slam_service.core import SlamConfig
from slam_service.map_paths import default_maps_root

REPO_ROOT = resources.data_root()
DEFAULT_ROBOT = "config/panda_mobile.yaml"


class ConfigError(ValueError):
    """Bad CMD_INIT config; the message starts with the field path (e.g. ``frames.map: ...``)."""


def default_map_dir() -> str:
    """``$ROBONIX_MAP_DIR``, else the maps root itself (``$ROBONIX_MAPS_ROOT``, default
    ``~/.local/share/robonix/maps``); it must lie under the maps root either way."""
    return os.environ.get("ROBONIX_MAP_DIR", "").strip() or str(default_maps_root())


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


ROLES = ("scan", "odom")
TopicRemap = per_role("TopicRemap", ROLES, OptionalTopicName,
                      doc="Per input role: a topic to read instead of looking the role up on the atlas.")
ProviderIds = per_role("ProviderIds", ROLES, doc="Per input role: the atlas provider to pin (empty: any).")


class Frames(_Model):
    map: FrameName = "map"
    odom: FrameName = "odom"
    base: FrameName = "base_link"


class InitialPose(_Model):
    x: FiniteFloat
    y: FiniteFloat
    theta: FiniteFloat = 0.0

    def as_tuple(self) -> tuple[float, float, float]:
        return (self.x, self.y, self.theta)


class ProviderConfig(_Model):
    topic_remap: TopicRemap = TopicRemap()  # type: ignore[valid-type]
    provider_ids: ProviderIds = ProviderIds()  # type: ignore[valid-type]
    frames: Frames = Frames()
    use_sim_time: bool = True
    map_dir: str = Field(default_factory=default_map_dir, max_length=4096)  # under the maps root
    mode: Literal["mapping", "localization"] = "mapping"
    map_id: str = Field("", max_length=64)  # load this saved map at INIT
    initial_pose: InitialPose | None = None
    slam: dict[str, Any] = Field(default_factory=dict)  # SlamConfig fields
    map_publish_period_s: Seconds = Field(1.0, gt=0)  # rate cap of /map
    tf_period_s: float = Field(0.05, gt=0, le=0.1)  # map->odom republish period (wall): >= 10 Hz
    autosave_period_s: float = Field(0.5, ge=0, le=3600)  # crash copy (0 = off); a crash loses <= this
    # scans waiting for the worker; oldest dropped beyond. 3 s at 10 Hz: the worker catches up at >= 100 scans/s,
    # so a backlog costs latency for a moment while a short queue (4 = 0.4 s) lost scans to any stall of the host
    # or of the worker (the numba kernels loading after the first map, a busy 2-core machine)
    scan_queue: int = Field(30, ge=1, le=600)
    robot_description: str = DEFAULT_ROBOT  # footprint for the map card


def resolve_path(path: str) -> Path:
    """Absolute as given; relative: the working directory first, then the repository root."""
    p = Path(path).expanduser()
    if p.is_absolute() or p.exists():
        return p
    return REPO_ROOT / p


def parse_config(raw: dict[str, Any]) -> tuple[ProviderConfig, SlamConfig]:
    """Validate the CMD_INIT dict; ConfigError names the field."""
    try:
        cfg = ProviderConfig.model_validate(raw)
    except ValidationError as exc:
        raise ConfigError(field_errors(exc)) from None
    try:
        slam = SlamConfig.from_dict(dict(cfg.slam))
    except ParamError as exc:  # ranges are declared on SlamConfig's fields, once
        raise ConfigError(f"slam.{exc.field}: {exc.reason[:300]}") from None
    except (TypeError, ValueError) as exc:
        raise ConfigError(f"slam: {str(exc)[:300]}") from None
    if cfg.initial_pose is not None and not cfg.map_id:
        raise ConfigError("initial_pose: only meaningful with map_id (the pose in that map)")
    if cfg.mode == "localization" and not cfg.map_id:
        raise ConfigError("mode: localization needs map_id (a saved map to localize in)")
    return cfg, slam


def load_footprint(path: str) -> list[tuple[float, float]]:
    """The base-frame footprint polygon from a robot description YAML (``footprint: [[x, y], ...]``)."""
    p = resolve_path(path)
    try:
        data = yaml.safe_load(p.read_text())
    except (OSError, yaml.YAMLError) as exc:
        raise ConfigError(f"robot_description: cannot read {p}: {exc}") from None
    fp = data.get("footprint") if isinstance(data, dict) else None
    try:
        poly = [(float(a), float(b)) for a, b in fp]  # type: ignore[union-attr]
    except (TypeError, ValueError):
        raise ConfigError(f"robot_description: {p} has no valid 'footprint' list of [x, y]") from None
    if len(poly) < 3 or not all(math.isfinite(v) for xy in poly for v in xy):
        raise ConfigError(f"robot_description: {p} footprint needs >= 3 finite points")
    return poly
