"""Nav2-shaped params profiles → the core's dataclass configs.

Loads ``config/nav2_params_<profile>.yml`` (or any path), fills the ``__ROBONIX_*__`` tokens, and validates
every section against its table in ``params_schema`` (types and ranges come from the core fields'
declarations; an error names the full parameter path). Builds the core configs from the same tables.
Warns — naming the full parameter path — about every key no active plugin reads (unknown keys, and
sections of unselected plugins: Nav2 silently ignores those; we do not) and lists the keys accepted only
for Nav2 compatibility. An unfilled token is an error naming the token.
"""

from __future__ import annotations

import re
import types
import typing
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from robonix_nav_data import resources

from . import params_schema as ps
from .core.checkers import GoalCheckerConfig, ProgressCheckerConfig
from .core.controller import ControllerConfig
from .core.costmap import CostmapConfig, ObservationSource
from .core.footprint import Footprint
from .core.mppi import MppiConfig
from .core.navigator import NavConfig, NavigatorConfig
from .core.planner import PlannerConfig
from .core.recoveries import RecoveryConfig
from .core.se2_planner import Se2PlannerConfig
from .robot_io import RobotLimits, load_footprint

CONFIG_DIR = resources.config_dir()
PROFILES = ("sim", "slam", "default")
TOKENS = ("__ROBONIX_MAP_TOPIC__", "__ROBONIX_ODOM_TOPIC__", "__ROBONIX_SCAN_TOPIC__", "__ROBONIX_FOOTPRINT__")
_TOKEN_RE = re.compile(r"__ROBONIX_[A-Z0-9_]+__")
NODES = ("bt_navigator", "planner_server", "controller_server", "global_costmap", "local_costmap", "behavior_server")

#: Values for core config fields, per config class, as the sections are read.
Fields = dict[type, dict[str, Any]]


class ParamsError(ValueError):
    """A params file is unusable; the message names the file, token or parameter path."""


@dataclass
class LoadedParams:
    config: NavConfig
    topics: dict[str, str]                      # map, odom, scan (empty when no scan source is active)
    warnings: list[str] = field(default_factory=list)   # keys nothing reads: unknown, or unselected plugin
    unused: list[str] = field(default_factory=list)     # keys set but accepted only for Nav2 compatibility
    source: str = ""


def fill_tokens(text: str, values: dict[str, str], where: str = "params") -> str:
    """Replace ``__ROBONIX_*__`` tokens; any token left (unknown or without a value) is an error naming it."""
    for tok, val in values.items():
        if val is not None:
            text = text.replace(tok, str(val))
    left = sorted(set(_TOKEN_RE.findall(text)))
    if left:
        raise ParamsError(f"{where}: unfilled token(s) {', '.join(left)} (known: {', '.join(TOKENS)})")
    return text


def profile_path(profile: str) -> Path:
    if profile not in PROFILES:
        raise ParamsError(f"unknown params_profile {profile!r}; expected one of {', '.join(PROFILES)}")
    return CONFIG_DIR / f"nav2_params_{profile}.yml"


def _coerce(value: Any, tp: Any) -> Any:
    """``value`` as YAML gives it, checked against (and converted to) the declared type ``tp``."""
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(tp) if a is not type(None)]
        return None if value is None else _coerce(value, args[0])
    if origin in (list, tuple):
        if not isinstance(value, list):
            raise ValueError(f"must be a list, got {value!r}")
        items = [_coerce(v, typing.get_args(tp)[0]) for v in value]
        return tuple(items) if origin is tuple else items
    if tp is bool and isinstance(value, bool):
        return value
    if tp is int and isinstance(value, (int, float)) and not isinstance(value, bool) and float(value).is_integer():
        return int(value)
    if tp is float and isinstance(value, (int, float)) and not isinstance(value, bool):
        return float(value)
    if tp is str and isinstance(value, str):
        return value
    want = {bool: "true or false", int: "an integer", float: "a number", str: "a string"}.get(tp, str(tp))
    raise ValueError(f"must be {want}, got {value!r}")


class _Reader:
    """Validates sections against their tables and collects what nobody reads."""

    def __init__(self, raw: dict[str, Any], where: str) -> None:
        self.raw, self.where = raw, where
        self.warnings: list[str] = []
        self.unused: list[str] = []

    def fail(self, path: str, why: str) -> ParamsError:
        return ParamsError(f"{self.where}: {path}: {why}")

    def read(self, sec: ps.Section, data: Any, path: str, into: Fields | None = None) -> dict[str, Any]:
        """Every key of ``sec`` (given or default) by YAML name; core keys also go to ``into``."""
        if data is None:
            data = {}
        if not isinstance(data, dict):
            raise self.fail(path, f"must be a mapping, got {type(data).__name__}")
        out: dict[str, Any] = {}
        for key in sec.keys:
            value = key.default.copy() if isinstance(key.default, list) else key.default
            if key.name in data:
                try:
                    value = _coerce(data[key.name], key.type)
                except ValueError as exc:
                    raise self.fail(f"{path}.{key.name}", str(exc)) from None
                why = key.spec.violation(value)
                if why:
                    raise self.fail(f"{path}.{key.name}", why)
                if key.compat:
                    self.unused.append(f"{path}.{key.name}")
            out[key.name] = value
            if key.target is not None and into is not None:
                into.setdefault(key.target, {})[key.field] = value
        for k in sorted(set(data) - set(out)):
            if not (sec.nested and isinstance(data[k], dict)):   # sub-sections are checked by their reader
                self.warn_subtree(f"{path}.{k}", data[k], f"is not a parameter of {sec.title} (ignored)")
        return out

    def warn(self, path: str, why: str) -> None:
        self.warnings.append(f"parameter '{path}' {why}")

    def warn_subtree(self, path: str, data: Any, why: str) -> None:
        if isinstance(data, dict):
            for k, v in data.items():
                self.warn_subtree(f"{path}.{k}", v, why)
        else:
            self.warn(path, why)

    def node(self, *keys: str) -> tuple[dict[str, Any], str]:
        d: Any = self.raw
        for k in keys:
            d = d.get(k, {}) if isinstance(d, dict) else {}
        params = d.get("ros__parameters", {}) if isinstance(d, dict) else {}
        return (params or {}), ".".join([*keys, "ros__parameters"])

    def plugin(self, params: dict[str, Any], path: str, name: str, sections: dict[str, ps.Section],
               kind: str) -> tuple[dict[str, Any], ps.Section]:
        """The selected plugin section ``name``: its raw mapping and the table its plugin type uses."""
        sec = params.get(name)
        if not isinstance(sec, dict) or "plugin" not in sec:
            raise self.fail(f"{path}.{name}", f"selected {kind} has no section with a 'plugin'")
        if sec["plugin"] not in sections:
            raise self.fail(f"{path}.{name}.plugin", f"{kind} {sec['plugin']!r} is not supported "
                                                     f"(supported: {', '.join(sorted(sections))})")
        return sec, sections[sec["plugin"]]

    def only(self, names: list[str], path: str) -> str:
        if len(names) != 1:
            raise self.fail(path, "exactly one entry is supported")
        return names[0]

    def unselected(self, params: dict[str, Any], path: str, selected: set[str]) -> None:
        for k, v in params.items():
            if isinstance(v, dict) and k not in selected:
                self.warn_subtree(f"{path}.{k}", v, "is under an unselected plugin and is not read")


def _plugins_for(sec: ps.Section) -> dict[str, ps.Section]:
    return dict.fromkeys(sec.plugins, sec)


def _footprint(text: str, padding: float, fallback: Footprint, rd: _Reader, path: str) -> Footprint:
    if text.strip() in ("", "[]"):
        fp = fallback
    else:
        try:
            fp = Footprint.from_string(text)
        except ValueError as exc:
            raise rd.fail(path, str(exc)) from exc
    if padding > 0:
        poly = fp.polygon + padding * (fp.polygon > 0) - padding * (fp.polygon < 0)
        fp = Footprint(poly)
    return fp


def _observation_sources(rd: _Reader, sec: dict[str, Any], lpath: str, names: list[str],
                         topics: dict[str, str]) -> list[ObservationSource]:
    out = []
    for src in names:
        into: Fields = {}
        v = rd.read(ps.OBSERVATION_SOURCE, sec.get(src), f"{lpath}.{src}", into)
        if not v["topic"]:
            rd.warn(f"{lpath}.{src}.topic", "is empty (no lidar on this deploy): source disabled")
            continue
        topics.setdefault("scan", v["topic"])
        out.append(ObservationSource(src, v["topic"], **into.get(ObservationSource, {})))
    rd.unselected(sec, lpath, set(names))
    return out


def _layers(rd: _Reader, raw: dict[str, Any], path: str, names: list[str], fields: dict[str, Any],
            topics: dict[str, str]) -> list[ObservationSource]:
    """Read the selected layer sections into ``fields`` (CostmapConfig's); returns the active scan sources."""
    fields.update(static_layer=False, obstacle_layer=False, inflation_layer=False)
    seen: set[str] = set()
    sources: list[ObservationSource] = []
    for lname in names:
        sec, table = rd.plugin(raw, path, lname, ps.LAYERS, "costmap layer")
        lpath = f"{path}.{lname}"
        if table.title in seen:
            raise rd.fail(lpath, f"a second {sec['plugin']} is not supported")
        seen.add(table.title)
        into: Fields = {}
        v = rd.read(table, sec, lpath, into)
        fields.update(into.get(CostmapConfig, {}))
        if table is ps.STATIC_LAYER:
            topics["map"] = v["map_topic"]
        elif table is ps.OBSTACLE_LAYER:
            sources = _observation_sources(rd, sec, lpath, v["observation_sources"].split(), topics)
            fields["obstacle_layer"] = v["enabled"] and bool(sources)
    if not fields["inflation_layer"]:
        fields["inflation_radius"] = 0.0
    return sources


def _costmap(rd: _Reader, name: str, fallback_fp: Footprint, topics: dict[str, str]) -> CostmapConfig:
    raw, path = rd.node(name, name)
    into: Fields = {}
    v = rd.read(ps.COSTMAP, raw, path, into)
    fp = _footprint(v["footprint"], v["footprint_padding"], fallback_fp, rd, f"{path}.footprint")
    fields = into.get(CostmapConfig, {})
    sources = _layers(rd, raw, path, v["plugins"], fields, topics)
    rd.unselected(raw, path, set(v["plugins"]))
    return CostmapConfig(name=name, footprint=fp, observation_sources=sources, **fields)


def _check_limits(rd: _Reader, c: ControllerConfig, limits: RobotLimits, path: str) -> None:
    """Warn where the controller may command more than the robot description allows."""
    pairs = (("max_vel_x", "max_vx"), ("max_vel_y", "max_vy"), ("max_vel_theta", "max_wz"),
             ("acc_lim_x", "max_ax"), ("acc_lim_y", "max_ay"), ("acc_lim_theta", "max_aw"))
    for mine, robot in pairs:
        if getattr(c, mine) > getattr(limits, robot) + 1e-9:
            rd.warn(f"{path}.{mine}", f"= {getattr(c, mine):g} exceeds the robot description's limits.{robot} "
                                      f"= {getattr(limits, robot):g} (the base clamps it)")


def _mppi_critics(rd: _Reader, sec: dict[str, Any], cpath: str, listed: list[str], into: Fields) -> None:
    """Read the listed critics' sections; a critic not listed (or disabled) has its weight set to 0."""
    unknown = [c for c in listed if c not in ps.CRITICS]
    if unknown:
        raise rd.fail(f"{cpath}.critics", f"unsupported critic(s) {', '.join(unknown)} "
                                          f"(supported: {', '.join(ps.CRITICS)})")
    weights = into.setdefault(MppiConfig, {})
    enabled: set[str] = set()
    for name in listed:
        v = rd.read(ps.CRITICS[name], sec.get(name), f"{cpath}.{name}", into)
        if v["enabled"] and name in ps.CRITIC_WEIGHTS:
            enabled.add(ps.CRITIC_WEIGHTS[name])
    for field_name in set(ps.CRITIC_WEIGHTS.values()) - enabled:
        weights[field_name] = 0.0
    rd.unselected(sec, cpath, set(listed))


def _controller_server(rd: _Reader, into: Fields, footprint: Footprint) -> tuple[ControllerConfig, str]:
    """The controller, goal checker and progress checker; returns the controller and its section path."""
    raw, path = rd.node("controller_server")
    v = rd.read(ps.CONTROLLER_SERVER, raw, path, into)
    names = {k: rd.only(v[k], f"{path}.{k}")
             for k in ("controller_plugins", "goal_checker_plugins", "progress_checker_plugins")}
    controllers = {**_plugins_for(ps.CONTROLLER), **_plugins_for(ps.MPPI_CONTROLLER)}
    sec, table = rd.plugin(raw, path, names["controller_plugins"], controllers, "controller")
    cpath = f"{path}.{names['controller_plugins']}"
    cv = rd.read(table, sec, cpath, into)
    if table is ps.MPPI_CONTROLLER:
        _mppi_critics(rd, sec, cpath, cv["critics"], into)
    sec, table = rd.plugin(raw, path, names["goal_checker_plugins"], ps.GOAL_CHECKERS, "goal checker")
    rd.read(table, sec, f"{path}.{names['goal_checker_plugins']}", into)
    into[GoalCheckerConfig]["stopped"] = table is ps.STOPPED_GOAL_CHECKER
    sec, table = rd.plugin(raw, path, names["progress_checker_plugins"], _plugins_for(ps.PROGRESS_CHECKER),
                           "progress checker")
    rd.read(table, sec, f"{path}.{names['progress_checker_plugins']}", into)
    rd.unselected(raw, path, set(names.values()))
    return ControllerConfig(footprint=footprint, **into.get(ControllerConfig, {})), \
        f"{path}.{names['controller_plugins']}"


def _planner_server(rd: _Reader, into: Fields) -> None:
    raw, path = rd.node("planner_server")
    v = rd.read(ps.PLANNER_SERVER, raw, path, into)
    name = rd.only(v["planner_plugins"], f"{path}.planner_plugins")
    chosen = raw.get(name, {}).get("plugin") if isinstance(raw.get(name), dict) else None
    if chosen in ps.REFUSED_PLANNERS:
        raise rd.fail(f"{path}.{name}.plugin", ps.REFUSED_PLANNERS[chosen])
    sec, table = rd.plugin(raw, path, name, _plugins_for(ps.PLANNER), "planner")
    rd.read(table, sec, f"{path}.{name}", into)
    style = ps.PLANNER_PATH_STYLE[sec["plugin"]]
    if style is not None:
        if "smooth_path" in sec and sec["smooth_path"] != style:
            rd.warn(f"{path}.{name}.smooth_path", f"is set by the plugin {sec['plugin']} to {str(style).lower()}")
        into.setdefault(PlannerConfig, {})["smooth_path"] = style
    rd.unselected(raw, path, {name})


def _behaviors(rd: _Reader, into: Fields, bt_path: str) -> None:
    raw, path = rd.node("behavior_server")
    v = rd.read(ps.BEHAVIOR_SERVER, raw, path, into)
    available = {"clear_costmaps", "escape"}   # escape: built in, like clear_costmaps (a plugin entry is optional)
    for name in v["behavior_plugins"]:
        sec, table = rd.plugin(raw, path, name, _plugins_for(ps.BEHAVIOR), "behavior")
        rd.read(table, sec, f"{path}.{name}")
        available.add(ps.BEHAVIORS[sec["plugin"]])
    rd.unselected(raw, path, set(v["behavior_plugins"]))
    for b in into[RecoveryConfig]["behaviors"]:
        if b not in available:
            raise rd.fail(f"{bt_path}.recovery_behaviors",
                          f"{b!r} needs a behavior_server plugin (have {', '.join(sorted(available))})")


def _parse(source: str | Path, text: str | None, tokens: dict[str, str]) -> tuple[dict[str, Any], str]:
    path = profile_path(str(source)) if str(source) in PROFILES else Path(source)
    where = str(path)
    if text is None:
        try:
            text = path.read_text()
        except OSError as exc:
            raise ParamsError(f"{where}: cannot read params file: {exc}") from exc
    text = fill_tokens(text, tokens, where)
    try:
        raw = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise ParamsError(f"{where}: invalid YAML: {exc}") from exc
    if not isinstance(raw, dict):
        raise ParamsError(f"{where}: top level must be a mapping of Nav2 node names")
    return raw, where


def load_params(source: str | Path, *, map_topic: str = "/map", odom_topic: str = "/odom",
                scan_topic: str = "/scan", footprint: Footprint | None = None, limits: RobotLimits | None = None,
                text: str | None = None) -> LoadedParams:
    """Load a profile name (sim|slam|default) or a params file path into the core's NavConfig.

    The tokens take the given topics and the footprint (default: the robot description's). With the
    robot's ``limits``, a controller limit above them is warned about. Raises ParamsError naming the file
    and the parameter/token; returns warnings for unread parameters.
    """
    fp = footprint or load_footprint()
    raw, where = _parse(source, text, {"__ROBONIX_MAP_TOPIC__": map_topic, "__ROBONIX_ODOM_TOPIC__": odom_topic,
                                       "__ROBONIX_SCAN_TOPIC__": scan_topic, "__ROBONIX_FOOTPRINT__": fp.to_string()})
    rd = _Reader(raw, where)
    for k, v in raw.items():
        if k not in NODES:
            rd.warn_subtree(k, v, "belongs to a node this navigation core does not run")
    into: Fields = {}
    bt_raw, bt_path = rd.node("bt_navigator")
    topics = {"odom": rd.read(ps.BT_NAVIGATOR, bt_raw, bt_path, into)["odom_topic"]}
    _planner_server(rd, into)
    controller, c_path = _controller_server(rd, into, fp)
    _behaviors(rd, into, bt_path)
    gcm = _costmap(rd, "global_costmap", fp, topics)
    lcm = _costmap(rd, "local_costmap", fp, topics)
    if lcm.footprint is not fp:
        controller.footprint = lcm.footprint
    if limits is not None:
        _check_limits(rd, controller, limits, c_path)
    cfg = NavConfig(
        global_costmap=gcm, local_costmap=lcm, controller=controller,
        planner=PlannerConfig(**into.get(PlannerConfig, {}), se2=Se2PlannerConfig(**into.get(Se2PlannerConfig, {}))),
        goal_checker=GoalCheckerConfig(**into.get(GoalCheckerConfig, {})),
        progress_checker=ProgressCheckerConfig(**into.get(ProgressCheckerConfig, {})),
        recovery=RecoveryConfig(**into.get(RecoveryConfig, {})),
        navigator=NavigatorConfig(**into.get(NavigatorConfig, {})),
        mppi=MppiConfig(**into[MppiConfig]) if MppiConfig in into else None,
    )
    topics.setdefault("map", map_topic)
    return LoadedParams(cfg, topics, rd.warnings, rd.unused, where)
