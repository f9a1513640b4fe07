"""Nav2-shaped params profiles → the core's dataclass configs.

Loads ``config/nav2_params_<profile>.yml`` (or any path), fills the ``__ROBONIX_*__`` tokens, validates
every section with pydantic, and warns — naming the full parameter path — about anything no active
plugin reads (Nav2 silently ignores parameters under an unselected plugin; we do not). An unfilled
token is an error naming the token.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from robonix_nav_data import resources

from .core.checkers import GoalCheckerConfig, ProgressCheckerConfig
from .core.controller import ControllerConfig
from .core.costmap import CostmapConfig, ObservationSource
from .core.footprint import Footprint
from .core.navigator import NavConfig, NavigatorConfig
from .core.planner import PlannerConfig
from .core.recoveries import RecoveryConfig

CONFIG_DIR = resources.config_dir()
PROFILES = ("sim", "slam", "default")
TOKENS = ("__ROBONIX_MAP_TOPIC__", "__ROBONIX_ODOM_TOPIC__", "__ROBONIX_SCAN_TOPIC__", "__ROBONIX_FOOTPRINT__")
_TOKEN_RE = re.compile(r"__ROBONIX_[A-Z0-9_]+__")

PLANNER_PLUGINS = {"robonix_nav/CostAwareAStar", "nav2_navfn_planner/NavfnPlanner",
                   "nav2_smac_planner/SmacPlanner2D", "nav2_theta_star_planner/ThetaStarPlanner"}
CONTROLLER_PLUGINS = {"robonix_nav::HolonomicPursuitController"}
GOAL_CHECKERS = {"nav2_controller::SimpleGoalChecker", "nav2_controller::StoppedGoalChecker"}
PROGRESS_CHECKERS = {"nav2_controller::SimpleProgressChecker"}
BEHAVIORS = {"nav2_behaviors/Spin": "spin", "nav2_behaviors/BackUp": "backup", "nav2_behaviors/Wait": "wait"}
LAYERS = {"nav2_costmap_2d::StaticLayer": "static", "nav2_costmap_2d::ObstacleLayer": "obstacle",
          "nav2_costmap_2d::InflationLayer": "inflation"}


class ParamsError(ValueError):
    """A params file is unusable; the message names the file, token or parameter path."""


class _P(BaseModel):
    model_config = ConfigDict(extra="allow")


class _Node(_P):
    use_sim_time: bool = False


class BtNavigatorParams(_Node):
    global_frame: str = "map"
    robot_base_frame: str = "base_link"
    odom_topic: str = "/odom"
    replan_frequency: float = Field(1.0, gt=0)
    path_blocked_lookahead: float = Field(2.5, gt=0)
    blocked_timeout: float = Field(2.0, gt=0)
    pending_timeout: float = Field(30.0, gt=0)
    # s a goal stays paused (robot stopped, RUNNING "waiting for <input>") while a required input is lost
    input_grace_s: float = Field(5.0, ge=0, le=3600)
    number_of_retries: int = Field(6, ge=0)
    recovery_behaviors: list[Literal["clear_costmaps", "spin", "wait", "backup"]] = \
        ["clear_costmaps", "spin", "wait", "backup"]
    spin_dist: float = Field(1.57, gt=0)
    wait_duration: float = Field(5.0, ge=0)
    backup_dist: float = Field(0.30, gt=0)
    backup_speed: float = Field(0.05, gt=0)


class PlannerServerParams(_Node):
    expected_planner_frequency: float = Field(20.0, gt=0)
    planner_plugins: list[str] = ["GridBased"]


class PlannerPluginParams(_P):
    plugin: str
    tolerance: float = Field(0.5, ge=0)
    allow_unknown: bool = True
    cost_travel_multiplier: float = Field(2.0, ge=0)
    unknown_cost: int = Field(200, ge=0, le=252)
    smooth_path: bool = True
    heuristic_weight: float = Field(1.25, ge=1.0)
    escape_radius: float = Field(0.35, ge=0)


class ControllerServerParams(_Node):
    controller_frequency: float = Field(20.0, gt=0)
    controller_plugins: list[str] = ["FollowPath"]
    goal_checker_plugins: list[str] = ["general_goal_checker"]
    progress_checker_plugins: list[str] = ["progress_checker"]


class GoalCheckerParams(_P):
    plugin: str
    xy_goal_tolerance: float = Field(0.25, gt=0)
    yaw_goal_tolerance: float = Field(0.25, gt=0)
    stateful: bool = True
    trans_stopped_velocity: float = Field(0.25, gt=0)   # StoppedGoalChecker only (Nav2 defaults)
    rot_stopped_velocity: float = Field(0.25, gt=0)


class ProgressCheckerParams(_P):
    plugin: str
    required_movement_radius: float = Field(0.5, gt=0)
    movement_time_allowance: float = Field(10.0, gt=0)


class ControllerPluginParams(_P):
    plugin: str
    max_vel_x: float = Field(0.5, gt=0)
    max_vel_y: float = Field(0.5, ge=0)
    max_vel_theta: float = Field(1.9, gt=0)
    acc_lim_x: float = Field(1.5, gt=0)
    acc_lim_y: float = Field(1.5, gt=0)
    acc_lim_theta: float = Field(3.0, gt=0)
    desired_linear_vel: float = Field(0.5, gt=0)
    lookahead_dist: float = Field(0.6, gt=0)
    min_lookahead_dist: float = Field(0.3, gt=0)
    max_lookahead_dist: float = Field(0.9, gt=0)
    lookahead_time: float = Field(1.5, gt=0)
    use_velocity_scaled_lookahead_dist: bool = True
    approach_velocity_scaling_dist: float = Field(0.6, gt=0)
    min_approach_linear_velocity: float = Field(0.05, ge=0)
    use_cost_regulated_linear_velocity_scaling: bool = True
    cost_scaling_dist: float = Field(0.6, gt=0)
    cost_scaling_gain: float = Field(1.0, gt=0)
    regulated_linear_scaling_min_speed: float = Field(0.15, ge=0)
    rotation_gain: float = Field(2.5, gt=0)
    allow_reversed_heading: bool = True
    rotate_to_goal_dist: float = Field(0.5, ge=0)
    collision_check_time: float = Field(1.0, gt=0)
    tight_clearance: float = Field(0.15, ge=0)      # m beyond the circumscribed radius = narrow passage
    passage_lookahead: float = Field(1.0, ge=0)     # m of path searched for a narrow passage


class CostmapParams(_Node):
    global_frame: str = "map"
    robot_base_frame: str = "base_link"
    update_frequency: float = Field(5.0, gt=0)
    publish_frequency: float = Field(1.0, gt=0)
    rolling_window: bool = False
    width: float = Field(5.0, gt=0)
    height: float = Field(5.0, gt=0)
    resolution: float = Field(0.05, gt=0)
    origin_x: float = 0.0
    origin_y: float = 0.0
    track_unknown_space: bool = False
    lethal_cost_threshold: int = Field(100, ge=1, le=100)
    unknown_cost_value: int = -1
    trinary_costmap: bool = True
    footprint: str = "[]"
    footprint_padding: float = Field(0.0, ge=0)
    plugins: list[str] = []


class StaticLayerParams(_P):
    plugin: str
    enabled: bool = True
    map_topic: str = "/map"
    map_subscribe_transient_local: bool = True


class ObstacleLayerParams(_P):
    plugin: str
    enabled: bool = True
    observation_sources: str = ""


class ObservationParams(_P):
    topic: str | None = None             # empty (no lidar on this deploy) disables the source
    data_type: Literal["LaserScan"] = "LaserScan"
    marking: bool = True
    clearing: bool = True
    obstacle_max_range: float = Field(2.5, gt=0)
    obstacle_min_range: float = Field(0.0, ge=0)
    raytrace_max_range: float = Field(3.0, gt=0)
    raytrace_min_range: float = Field(0.0, ge=0)
    inf_is_valid: bool = False
    max_obstacle_height: float = 2.0    # read for Nav2 compatibility; a 2-D scan has no height


class InflationLayerParams(_P):
    plugin: str
    enabled: bool = True
    inflation_radius: float = Field(0.55, gt=0)
    cost_scaling_factor: float = Field(10.0, gt=0)
    inflate_unknown: bool = False


class BehaviorServerParams(_Node):
    behavior_plugins: list[str] = ["spin", "backup", "wait"]
    cycle_frequency: float = Field(10.0, gt=0)
    simulate_ahead_time: float = Field(2.0, gt=0)
    max_rotational_vel: float = Field(1.0, gt=0)
    min_rotational_vel: float = Field(0.4, gt=0)
    rotational_acc_lim: float = Field(3.2, gt=0)
    time_allowance: float = Field(10.0, gt=0)


class BehaviorPluginParams(_P):
    plugin: str


@dataclass
class LoadedParams:
    config: NavConfig
    topics: dict[str, str]                      # map, odom, scan (empty when no scan source is active)
    warnings: list[str] = field(default_factory=list)
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


class _Reader:
    """Validates sections and collects the warnings for parameters nobody reads."""

    def __init__(self, raw: dict[str, Any], where: str) -> None:
        self.raw, self.where, self.warnings = raw, where, []

    def model(self, cls: type[_P], data: Any, path: str) -> Any:
        if data is None:
            data = {}
        if not isinstance(data, dict):
            raise ParamsError(f"{self.where}: {path} must be a mapping, got {type(data).__name__}")
        try:
            m = cls.model_validate(data)
        except ValidationError as exc:
            err = exc.errors()[0]
            loc = ".".join(str(p) for p in err["loc"])
            raise ParamsError(f"{self.where}: {path}.{loc}: {err['msg']}") from exc
        for k in sorted(m.model_extra or {}):
            if not isinstance(data[k], dict):
                self.warn(f"{path}.{k}", "is not read by any active plugin")
        return m

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

    def plugins(self, params: dict[str, Any], path: str, names: list[str], cls: type[_P] | None,
                allowed: set[str] | dict,
                kind: str) -> list[tuple[str, Any]]:
        """Validate the selected plugin sections; warn about sub-sections of unselected ones."""
        out = []
        for name in names:
            sec = params.get(name)
            if not isinstance(sec, dict) or "plugin" not in sec:
                raise ParamsError(f"{self.where}: {path}.{name}: selected {kind} has no section with a 'plugin'")
            if sec["plugin"] not in allowed:
                raise ParamsError(f"{self.where}: {path}.{name}.plugin: {kind} {sec['plugin']!r} is not supported "
                                  f"(supported: {', '.join(sorted(allowed))})")
            out.append((name, sec if cls is None else self.model(cls, sec, f"{path}.{name}")))
        return out

    def unselected(self, params: dict[str, Any], path: str, selected: set[str]) -> None:
        for k, v in params.items():
            if isinstance(v, dict) and k not in selected:
                self.warn_subtree(f"{path}.{k}", v, "is under an unselected plugin and is not read")


def _footprint(text: str, padding: float, fallback: Footprint, where: str) -> Footprint:
    if text.strip() in ("", "[]"):
        fp = fallback
    else:
        try:
            fp = Footprint.from_string(text)
        except ValueError as exc:
            raise ParamsError(f"{where}: {exc}") from exc
    if padding > 0:
        poly = fp.polygon + padding * (fp.polygon > 0) - padding * (fp.polygon < 0)
        fp = Footprint(poly)
    return fp


def _costmap(rd: _Reader, name: str, fallback_fp: Footprint, topics: dict[str, str]) -> CostmapConfig:
    raw, path = rd.node(name, name)
    p = rd.model(CostmapParams, raw, path)
    fp = _footprint(p.footprint, p.footprint_padding, fallback_fp, f"{rd.where}: {path}.footprint")
    cfg = CostmapConfig(name=name, resolution=p.resolution, rolling_window=p.rolling_window, width=p.width,
                        height=p.height, origin_x=p.origin_x, origin_y=p.origin_y, static_layer=False,
                        obstacle_layer=False, inflation_layer=False, track_unknown_space=p.track_unknown_space,
                        lethal_cost_threshold=p.lethal_cost_threshold, unknown_cost_value=p.unknown_cost_value,
                        trinary_costmap=p.trinary_costmap, footprint=fp, observation_sources=[])
    layers = rd.plugins(raw, path, p.plugins, None, LAYERS, "costmap layer")
    seen: set[str] = set()
    for lname, _ in layers:
        sec = raw[lname]
        kind = LAYERS[sec["plugin"]]
        lpath = f"{path}.{lname}"
        if kind in seen:
            raise ParamsError(f"{rd.where}: {lpath}: a second {sec['plugin']} is not supported")
        seen.add(kind)
        if kind == "static":
            sp = rd.model(StaticLayerParams, sec, lpath)
            cfg.static_layer = sp.enabled
            topics["map"] = sp.map_topic
        elif kind == "inflation":
            ip = rd.model(InflationLayerParams, sec, lpath)
            cfg.inflation_layer = ip.enabled
            cfg.inflation_radius, cfg.cost_scaling_factor = ip.inflation_radius, ip.cost_scaling_factor
            cfg.inflate_unknown = ip.inflate_unknown
        else:
            op = rd.model(ObstacleLayerParams, sec, lpath)
            names = op.observation_sources.split()
            for src in names:
                o = rd.model(ObservationParams, sec.get(src), f"{lpath}.{src}")
                if not o.topic:
                    rd.warn(f"{lpath}.{src}.topic", "is empty (no lidar on this deploy): source disabled")
                    continue
                topics.setdefault("scan", o.topic)
                cfg.observation_sources.append(ObservationSource(
                    src, o.topic, o.marking, o.clearing, o.obstacle_max_range, o.obstacle_min_range,
                    o.raytrace_max_range, o.raytrace_min_range, o.inf_is_valid))
            rd.unselected(sec, lpath, set(names))
            cfg.obstacle_layer = op.enabled and bool(cfg.observation_sources)
    rd.unselected(raw, path, set(p.plugins))
    if not cfg.inflation_layer:
        cfg.inflation_radius = 0.0
    return cfg


def load_params(source: str | Path, *, map_topic: str = "/map", odom_topic: str = "/odom",
                scan_topic: str = "/scan", footprint: Footprint | None = None,
                text: str | None = None) -> LoadedParams:
    """Load a profile name (sim|slam|default) or a params file path into the core's NavConfig.

    The tokens take the given topics and the footprint (default: config/panda_mobile.yaml). Raises
    ParamsError naming the file and the parameter/token; returns warnings for unread parameters.
    """
    path = profile_path(str(source)) if str(source) in PROFILES else Path(source)
    where = str(path)
    fp = footprint or Footprint.from_robot_yaml()
    if text is None:
        try:
            text = path.read_text()
        except OSError as exc:
            raise ParamsError(f"{where}: cannot read params file: {exc}") from exc
    text = fill_tokens(text, {"__ROBONIX_MAP_TOPIC__": map_topic, "__ROBONIX_ODOM_TOPIC__": odom_topic,
                              "__ROBONIX_SCAN_TOPIC__": scan_topic, "__ROBONIX_FOOTPRINT__": fp.to_string()}, where)
    try:
        raw = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise ParamsError(f"{where}: invalid YAML: {exc}") from exc
    if not isinstance(raw, dict):
        raise ParamsError(f"{where}: top level must be a mapping of Nav2 node names")
    rd = _Reader(raw, where)
    known = {"bt_navigator", "planner_server", "controller_server", "global_costmap", "local_costmap",
             "behavior_server"}
    for k, v in raw.items():
        if k not in known:
            rd.warn_subtree(k, v, "belongs to a node this navigation core does not run")
    topics: dict[str, str] = {}

    bt_raw, bt_path = rd.node("bt_navigator")
    bt = rd.model(BtNavigatorParams, bt_raw, bt_path)
    topics["odom"] = bt.odom_topic

    pl_raw, pl_path = rd.node("planner_server")
    ps = rd.model(PlannerServerParams, pl_raw, pl_path)
    if len(ps.planner_plugins) != 1:
        raise ParamsError(f"{where}: {pl_path}.planner_plugins: exactly one planner is supported")
    (_, pp), = rd.plugins(pl_raw, pl_path, ps.planner_plugins, PlannerPluginParams, PLANNER_PLUGINS, "planner")
    rd.unselected(pl_raw, pl_path, set(ps.planner_plugins))

    c_raw, c_path = rd.node("controller_server")
    cs = rd.model(ControllerServerParams, c_raw, c_path)
    for lst, nm in ((cs.controller_plugins, "controller_plugins"), (cs.goal_checker_plugins, "goal_checker_plugins"),
                    (cs.progress_checker_plugins, "progress_checker_plugins")):
        if len(lst) != 1:
            raise ParamsError(f"{where}: {c_path}.{nm}: exactly one entry is supported")
    (_, cp), = rd.plugins(c_raw, c_path, cs.controller_plugins, ControllerPluginParams, CONTROLLER_PLUGINS,
                          "controller")
    (_, gp), = rd.plugins(c_raw, c_path, cs.goal_checker_plugins, GoalCheckerParams, GOAL_CHECKERS, "goal checker")
    (_, pg), = rd.plugins(c_raw, c_path, cs.progress_checker_plugins, ProgressCheckerParams, PROGRESS_CHECKERS,
                          "progress checker")
    rd.unselected(c_raw, c_path, {*cs.controller_plugins, *cs.goal_checker_plugins, *cs.progress_checker_plugins})

    b_raw, b_path = rd.node("behavior_server")
    bs = rd.model(BehaviorServerParams, b_raw, b_path)
    beh = rd.plugins(b_raw, b_path, bs.behavior_plugins, BehaviorPluginParams, BEHAVIORS, "behavior")
    rd.unselected(b_raw, b_path, set(bs.behavior_plugins))
    available = {"clear_costmaps"} | {BEHAVIORS[m.plugin] for _, m in beh}
    for b in bt.recovery_behaviors:
        if b not in available:
            raise ParamsError(f"{where}: {bt_path}.recovery_behaviors: {b!r} needs a behavior_server plugin "
                              f"(have {', '.join(sorted(available))})")

    gcm = _costmap(rd, "global_costmap", fp, topics)
    lcm = _costmap(rd, "local_costmap", fp, topics)
    ctrl_fields = {k: v for k, v in cp.model_dump().items() if k in ControllerConfig.__dataclass_fields__}
    cfg = NavConfig(
        global_costmap=gcm,
        local_costmap=lcm,
        planner=PlannerConfig(tolerance=pp.tolerance, allow_unknown=pp.allow_unknown,
                              cost_travel_multiplier=pp.cost_travel_multiplier, unknown_cost=pp.unknown_cost,
                              smooth_path=pp.smooth_path, heuristic_weight=pp.heuristic_weight,
                              escape_radius=pp.escape_radius),
        controller=ControllerConfig(**ctrl_fields, footprint=lcm.footprint),
        goal_checker=GoalCheckerConfig(
            gp.xy_goal_tolerance, gp.yaw_goal_tolerance, gp.stateful,
            *((gp.trans_stopped_velocity, gp.rot_stopped_velocity) if gp.plugin.endswith("StoppedGoalChecker")
              else (None, None))),
        progress_checker=ProgressCheckerConfig(pg.required_movement_radius, pg.movement_time_allowance),
        recovery=RecoveryConfig(number_of_retries=bt.number_of_retries, behaviors=tuple(bt.recovery_behaviors),
                                spin_dist=bt.spin_dist, max_rotational_vel=bs.max_rotational_vel,
                                min_rotational_vel=bs.min_rotational_vel, rotational_acc_lim=bs.rotational_acc_lim,
                                wait_duration=bt.wait_duration, backup_dist=bt.backup_dist,
                                backup_speed=bt.backup_speed, time_allowance=bs.time_allowance,
                                simulate_ahead_time=bs.simulate_ahead_time),
        navigator=NavigatorConfig(replan_frequency=bt.replan_frequency, controller_frequency=cs.controller_frequency,
                                  path_blocked_lookahead=bt.path_blocked_lookahead, blocked_timeout=bt.blocked_timeout,
                                  pending_timeout=bt.pending_timeout, input_grace_s=bt.input_grace_s,
                                  global_frame=bt.global_frame,
                                  robot_base_frame=bt.robot_base_frame),
    )
    if gcm.resolution <= 0 or (cfg.controller.max_vel_x <= 0):
        raise ParamsError(f"{where}: invalid resolution or velocity")
    topics.setdefault("map", map_topic)
    return LoadedParams(cfg, topics, rd.warnings, where)
