"""The atlas' settings, from flags, ``--config-json``, environment and defaults (in that order).

robonix's ``rbnx`` starts the atlas with the deploy file's ``system.atlas`` block handed over as one JSON
object (``robonix-atlas --config-json '{"listen": "127.0.0.1:50051", "log": "info"}'``); our own flags
and the ``ROBONIX_ATLAS_*`` variables keep working. Keys we do not know are reported, not fatal, so a
newer robonix deploy file still starts our atlas.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from robonix_api.validation import field_errors

DEFAULT_LISTEN = "127.0.0.1:50051"
MAX_CONFIG_JSON = 64 * 1024  # a settings object, not a data file

#: setting -> (environment variable, default)
_ENV: dict[str, tuple[str, Any]] = {
    "listen": ("ROBONIX_ATLAS_LISTEN", DEFAULT_LISTEN),
    "capabilities": ("ROBONIX_ATLAS_CAPABILITIES", ""),
    "heartbeat_timeout_ms": ("ROBONIX_ATLAS_HEARTBEAT_TIMEOUT_MS", 90000),
    "eviction_interval_ms": ("ROBONIX_ATLAS_EVICTION_INTERVAL_MS", 10000),
    "gc_after_terminated_ms": ("ROBONIX_ATLAS_GC_AFTER_TERMINATED_MS", 600000),
    "log_level": ("ROBONIX_LOG_LEVEL", "INFO"),
    "allowed_hosts": ("ROBONIX_ATLAS_ALLOWED_HOSTS", ""),
}
_LEVELS = ("trace", "debug", "info", "warn", "warning", "error", "critical", "off")


class JsonSettings(BaseModel):
    """What ``--config-json`` may carry (robonix's ``system.atlas`` keys plus ours)."""

    model_config = ConfigDict(extra="allow")

    listen: str | None = Field(default=None, max_length=256)
    log: str | None = Field(default=None, max_length=256)  # robonix: env_logger filter, e.g. "robonix_atlas=debug"
    log_level: str | None = Field(default=None, max_length=32)
    capabilities: str | list[str] | None = None
    heartbeat_timeout_ms: int | None = Field(default=None, ge=0, le=86_400_000)
    eviction_interval_ms: int | None = Field(default=None, ge=10, le=3_600_000)
    gc_after_terminated_ms: int | None = Field(default=None, ge=0, le=604_800_000)
    allowed_hosts: str | list[str] | None = None
    # rbnx's deploy option (the token itself only ever travels in $ROBONIX_DEPLOY_TOKEN, never in argv)
    auth: str | None = Field(default=None, pattern="^(token|none)$")

    @field_validator("capabilities", "allowed_hosts")
    @classmethod
    def _join(cls, v: str | list[str] | None) -> str | None:
        return ",".join(v) if isinstance(v, list) else v


@dataclass(frozen=True)
class AtlasSettings:
    listen: str
    catalogue_roots: list[Path] | None
    heartbeat_timeout_ms: int
    eviction_interval_ms: int
    gc_after_terminated_ms: int
    log_level: str
    allowed_hosts: tuple[str, ...] = ()
    auth: str = "token"  # "none": ignore $ROBONIX_DEPLOY_TOKEN, accept every change (robonix's atlas)
    ignored_keys: tuple[str, ...] = ()  # --config-json keys we do not know (logged once logging is up)


def parse_config_json(text: str) -> JsonSettings:
    """Validate ``--config-json``; ValueError with the field named on anything wrong."""
    if len(text) > MAX_CONFIG_JSON:
        raise ValueError(f"--config-json: longer than {MAX_CONFIG_JSON} characters")
    try:
        raw = json.loads(text) if text.strip() else {}
    except json.JSONDecodeError as exc:
        raise ValueError(f"--config-json: invalid JSON at line {exc.lineno} column {exc.colno}: {exc.msg}") from None
    except RecursionError:
        raise ValueError("--config-json: nested too deeply") from None
    if not isinstance(raw, dict):
        raise ValueError(f"--config-json: expected a JSON object, got {type(raw).__name__}")
    try:
        parsed = JsonSettings.model_validate(raw)
    except ValidationError as exc:
        raise ValueError(f"--config-json: {field_errors(exc)}") from None
    return parsed


def level_from_filter(spec: str) -> str:
    """The most verbose level named in an env_logger-style filter (``warn,robonix_atlas=debug`` -> DEBUG)."""
    found = [part.rsplit("=", 1)[-1].strip().lower() for part in spec.split(",") if part.strip()]
    known = [lvl for lvl in found if lvl in _LEVELS]
    if not known:
        raise ValueError(f"--config-json: log: no level in {spec[:64]!r} (one of {', '.join(_LEVELS)})")
    rank = {"trace": 0, "debug": 0, "info": 1, "warn": 2, "warning": 2, "error": 3, "critical": 4, "off": 5}
    best = min(known, key=rank.__getitem__)
    return {"trace": "DEBUG", "warn": "WARNING", "off": "CRITICAL"}.get(best, best.upper())


def _env(name: str, default: Any) -> Any:
    raw = os.environ.get(name, "").strip()
    if not raw:
        return default
    if isinstance(default, int):
        try:
            return int(raw)
        except ValueError:
            raise ValueError(f"{name}: expected an integer, got {raw[:64]!r}") from None
    return raw


def resolve(flags: dict[str, Any], config_json: str | None) -> AtlasSettings:
    """Flags win over ``--config-json``, which wins over the environment, which wins over defaults."""
    js = parse_config_json(config_json) if config_json is not None else JsonSettings()
    from_json: dict[str, Any] = {k: getattr(js, k) for k in _ENV if k != "log_level"}
    from_json["log_level"] = js.log_level or (level_from_filter(js.log) if js.log else None)
    values: dict[str, Any] = {}
    for key, (env, default) in _ENV.items():
        if flags.get(key) is not None:
            values[key] = flags[key]
        elif from_json.get(key) is not None:
            values[key] = from_json[key]
        else:
            values[key] = _env(env, default)
    roots = [Path(p.strip()) for p in str(values["capabilities"]).split(",") if p.strip()] or None
    from atlas.trust import parse_allowed_hosts

    hosts = parse_allowed_hosts(str(values["allowed_hosts"] or ""))
    return AtlasSettings(listen=values["listen"], catalogue_roots=roots,
                         heartbeat_timeout_ms=int(values["heartbeat_timeout_ms"]),
                         eviction_interval_ms=int(values["eviction_interval_ms"]),
                         gc_after_terminated_ms=int(values["gc_after_terminated_ms"]),
                         log_level=str(values["log_level"]), allowed_hosts=hosts, auth=js.auth or "token",
                         ignored_keys=tuple(sorted(js.model_extra or {})))
