"""Which YAML key of a Nav2 params profile sets which core parameter: one table per node and plugin.

A key that sets a core field takes its type, default, unit, range and doc from the field's declaration
(``robonix_common.params.param``), so they are written once, in the core. The few keys the wrapper reads itself
(topics, plugin lists, the footprint string) and the keys accepted only for Nav2 compatibility are
declared here, once. ``nav2_wrapper.params`` validates and builds from these tables, and
``nav2_wrapper.paramdoc`` renders them as the parameter reference in CAPABILITY.md.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from robonix_common.params import Spec, declared

from .core.checkers import GoalCheckerConfig, ProgressCheckerConfig
from .core.controller import ControllerConfig
from .core.costmap import CostmapConfig, ObservationSource
from .core.mppi import MppiConfig
from .core.navigator import NavigatorConfig
from .core.planner import PlannerConfig
from .core.recoveries import RecoveryConfig
from .core.se2_planner import Se2PlannerConfig

COMPAT_NOTE = "accepted for Nav2 compatibility, not used"


@dataclass(frozen=True)
class Key:
    """One YAML key: its type, default and declaration, and the core field it sets (if any)."""

    name: str
    type: Any
    default: Any
    spec: Spec
    target: type | None = None     # core config dataclass the value goes to; None: the wrapper reads it
    field: str = ""                # the field there
    compat: bool = False           # accepted for Nav2 compatibility, not used


def core(cls: type, name: str, *, key: str = "") -> Key:
    """The key that sets ``cls.name``; everything but the YAML key's name comes from the field."""
    tp, default, spec = declared(cls)[name]
    return Key(key or name, tp, default, spec, cls, name)


def core_all(cls: type, *, skip: tuple[str, ...] = ()) -> tuple[Key, ...]:
    """Keys for every declared field of ``cls`` (same names), except ``skip``."""
    return tuple(core(cls, n) for n in declared(cls) if n not in skip)


def own(name: str, tp: Any, default: Any, doc: str, **bounds: Any) -> Key:
    """A key the wrapper reads itself (a topic, a plugin list, the footprint string)."""
    return Key(name, tp, default, Spec(doc, **bounds))


def compat(name: str, tp: Any, default: Any, doc: str) -> Key:
    """A Nav2 key we accept (and type-check) but do not use; setting it is reported, not an error."""
    return Key(name, tp, default, Spec(doc), compat=True)


@dataclass(frozen=True)
class Section:
    """The keys of one node's ``ros__parameters`` or of one plugin's sub-section."""

    title: str                      # where it lives in the YAML, for messages and the reference
    keys: tuple[Key, ...]
    plugins: tuple[str, ...] = ()   # plugin type names this section describes (plugin sections only)
    doc: str = ""
    nested: bool = False            # mappings inside are sub-sections (plugins, sources), checked separately

    def __post_init__(self) -> None:
        names = [k.name for k in self.keys]
        if len(names) != len(set(names)):
            raise ValueError(f"{self.title}: duplicate key in {names}")

    def get(self, name: str) -> Key | None:
        return next((k for k in self.keys if k.name == name), None)


def _sim_time() -> Key:
    return compat("use_sim_time", bool, False, "the provider config's use_sim_time decides")


def _plugin() -> Key:
    return own("plugin", str, None, "plugin type (one of the names in this section's title)")


BT_NAVIGATOR = Section("bt_navigator", (
    _sim_time(),
    own("odom_topic", str, "/odom", "odometry topic (an atlas-resolved binding wins; a mismatch is logged)"),
    *core_all(NavigatorConfig, skip=("controller_frequency",)),
    core(RecoveryConfig, "number_of_retries"),
    core(RecoveryConfig, "behaviors", key="recovery_behaviors"),
    *(core(RecoveryConfig, n) for n in ("spin_dist", "wait_duration", "backup_dist", "backup_speed")),
), doc="The navigate-to-pose behaviour and the recovery sequence.")

PLANNER_SERVER = Section("planner_server", (
    _sim_time(),
    compat("expected_planner_frequency", float, 20.0, "plans run when the navigator asks (replan_frequency)"),
    own("planner_plugins", list[str], ["GridBased"], "the planner's section name (exactly one)"),
), nested=True)

#: Planner plugin names and what each one fixes: the path style (``smooth_path``; None: the key decides). All
#: run the one cost-aware 8-connected A*; they differ in what is returned.
PLANNER_PATH_STYLE: dict[str, bool | None] = {
    "robonix_nav/CostAwareAStar": None,                      # smooth_path decides (default: shortcut)
    "nav2_smac_planner/SmacPlanner2D": False,                # the 8-connected grid path, as Smac 2D returns it
    "nav2_theta_star_planner/ThetaStarPlanner": True,        # any-angle: line-of-sight shortcuts, Theta*-style
}
PLANNER_PLUGINS = tuple(PLANNER_PATH_STYLE)
#: Nav2 planner names we do not provide, with what to use instead.
REFUSED_PLANNERS = {
    "nav2_navfn_planner/NavfnPlanner": "NavFn (a navigation-function wavefront with gradient descent) is not "
    "provided; use robonix_nav/CostAwareAStar (cost-aware A*, shortcut path), nav2_smac_planner/SmacPlanner2D "
    "(the same A*, 8-connected grid path) or nav2_theta_star_planner/ThetaStarPlanner (any-angle path)",
}
PLANNER = Section("planner_server.<planner>", (
    _plugin(), *core_all(PlannerConfig),
    *(core(Se2PlannerConfig, n, key=f"se2_{n}") for n in declared(Se2PlannerConfig)),
), PLANNER_PLUGINS, doc="One cost-aware 8-connected A*; the plugin name picks the path it returns: "
                        "SmacPlanner2D the 8-connected grid path, ThetaStarPlanner an any-angle path "
                        "(line-of-sight shortcuts), CostAwareAStar as `smooth_path` says (NavfnPlanner is "
                        "refused). The se2_* keys set its footprint-aware (x, y, heading) fallback.")

CONTROLLER_SERVER = Section("controller_server", (
    _sim_time(),
    core(NavigatorConfig, "controller_frequency"),
    own("controller_plugins", list[str], ["FollowPath"], "the controller's section name (exactly one)"),
    own("goal_checker_plugins", list[str], ["general_goal_checker"], "the goal checker's section (exactly one)"),
    own("progress_checker_plugins", list[str], ["progress_checker"],
        "the progress checker's section (exactly one)"),
), nested=True)

CONTROLLER = Section("controller_server.<controller>", (_plugin(), *core_all(ControllerConfig)),
                     ("robonix_nav::HolonomicPursuitController",))

#: Nav2 MPPI's names for the velocity and acceleration limits, and the ControllerConfig field each sets.
MPPI_LIMITS = {"vx_max": "max_vel_x", "vy_max": "max_vel_y", "wz_max": "max_vel_theta", "ax_max": "acc_lim_x",
               "ay_max": "acc_lim_y", "az_max": "acc_lim_theta"}
_MPPI_WEIGHTS = ("collision_cost", "cost_weight", "path_follow_weight", "progress_weight", "path_align_weight",
                 "goal_weight", "goal_distance", "heading_weight", "twirling_weight", "smoothness_weight")
MPPI_CONTROLLER = Section("controller_server.<controller> (MPPI)", (
    _plugin(),
    *(core(ControllerConfig, field, key=key) for key, field in MPPI_LIMITS.items()),
    *core_all(ControllerConfig, skip=tuple(MPPI_LIMITS.values())),
    *core_all(MppiConfig, skip=_MPPI_WEIGHTS),
    core(MppiConfig, "collision_cost"),
    own("motion_model", str, "Omni", "the base's kinematics", choices=("Omni",)),
    own("critics", list[str], ["CostCritic", "GoalCritic", "GoalAngleCritic", "PathAlignCritic",
                                "PathFollowCritic", "PathAngleCritic", "TwirlingCritic", "SmoothnessCritic"],
        "critic section names; a critic not listed is off (the collision critic is always on)"),
    compat("iteration_count", int, 1, "one optimisation per control step"),
    compat("vx_min", float, -0.35, "the omni base's vx range is symmetric: -vx_max … vx_max"),
    compat("gamma", float, 0.015, "no control-cost term; smoothness is a critic"),
    compat("prune_distance", float, 1.7, "the path ahead is cut at the horizon"),
    compat("transform_tolerance", float, 0.1, "poses come in the costmap frame"),
    compat("enforce_path_inversion", bool, False, "either end may lead"),
    compat("visualize", bool, False, "no marker output"),
    compat("retry_attempt_limit", int, 1, "a failed step falls back to the pursuit's candidates"),
    compat("regenerate_noises", bool, False, "fresh noise every step"),
), ("nav2_mppi_controller::MPPIController",),
    doc="Sampling predictive controller for the omni base; the pursuit keys configure its fallback.",
    nested=True)


def _critic(field: str | None, *extra: Key) -> Section:
    keys: tuple[Key, ...] = (own("enabled", bool, True, "false switches this critic off"),)
    if field is not None:
        keys += (core(MppiConfig, field, key="cost_weight"),)
    return Section("<MPPI controller>.<critic>", (*keys, *extra,
                                                  compat("cost_power", int, 1, "costs enter linearly")))


#: Nav2 critic names -> their section (the MppiConfig weight their ``cost_weight`` sets). Nav2's GoalAngle and
#: PathAngle critics both feed the one heading critic; ConstraintCritic's limits are enforced by the sampler.
CRITICS = {
    "ConstraintCritic": _critic(None),
    "CostCritic": _critic("cost_weight"),
    "ObstaclesCritic": _critic("cost_weight"),
    "GoalCritic": _critic("goal_weight", core(MppiConfig, "goal_distance", key="threshold_to_consider")),
    "GoalAngleCritic": _critic("heading_weight"),
    "PathAngleCritic": _critic("heading_weight"),
    "PathAlignCritic": _critic("path_align_weight"),
    "PathFollowCritic": _critic("path_follow_weight", core(MppiConfig, "progress_weight")),
    "PreferForwardCritic": _critic(None),
    "TwirlingCritic": _critic("twirling_weight"),
    "SmoothnessCritic": _critic("smoothness_weight"),
}
#: The weight each critic switches off when it is not listed (or has enabled: false).
CRITIC_WEIGHTS = {"CostCritic": "cost_weight", "ObstaclesCritic": "cost_weight", "GoalCritic": "goal_weight",
                  "GoalAngleCritic": "heading_weight", "PathAngleCritic": "heading_weight",
                  "PathAlignCritic": "path_align_weight", "PathFollowCritic": "path_follow_weight",
                  "TwirlingCritic": "twirling_weight", "SmoothnessCritic": "smoothness_weight"}

_GOAL = tuple(core(GoalCheckerConfig, n) for n in ("xy_goal_tolerance", "yaw_goal_tolerance", "stateful"))
_STOPPED = (core(GoalCheckerConfig, "trans_stopped_velocity"), core(GoalCheckerConfig, "rot_stopped_velocity"))
SIMPLE_GOAL_CHECKER = Section("controller_server.<goal checker>", (_plugin(), *_GOAL),
                              ("nav2_controller::SimpleGoalChecker",))
STOPPED_GOAL_CHECKER = Section("controller_server.<goal checker>", (_plugin(), *_GOAL, *_STOPPED),
                               ("nav2_controller::StoppedGoalChecker",),
                               doc="Success also needs the base at rest.")
GOAL_CHECKERS = {p: s for s in (SIMPLE_GOAL_CHECKER, STOPPED_GOAL_CHECKER) for p in s.plugins}

PROGRESS_CHECKER = Section("controller_server.<progress checker>", (_plugin(), *core_all(ProgressCheckerConfig)),
                           ("nav2_controller::SimpleProgressChecker",))

_LAYER_FIELDS = ("static_layer", "obstacle_layer", "inflation_layer", "inflation_radius",
                            "cost_scaling_factor", "inflate_unknown")
COSTMAP = Section("global_costmap.global_costmap, local_costmap.local_costmap", (
    _sim_time(),
    compat("global_frame", str, "map", "the provider config's frames decide"),
    compat("robot_base_frame", str, "base_link", "the provider config's frames decide"),
    compat("update_frequency", float, 5.0, "layers update as data arrives; the local costmap every control tick"),
    compat("publish_frequency", float, 1.0, "costmaps are not published"),
    *core_all(CostmapConfig, skip=_LAYER_FIELDS),
    own("footprint", str, "[]", "base-frame polygon \"[[x, y], ...]\"; \"[]\": the robot description's"),
    own("footprint_padding", float, 0.0, "grow the footprint by this on every side", unit="m", ge=0),
    own("plugins", list[str], [], "layer section names, each with a 'plugin'"),
), doc="Both costmaps; the layers are plugin sub-sections listed in 'plugins'.", nested=True)

STATIC_LAYER = Section("<costmap>.<static layer>", (
    _plugin(),
    core(CostmapConfig, "static_layer", key="enabled"),
    own("map_topic", str, "/map", "map topic (an atlas-resolved binding wins; a mismatch is logged)"),
    compat("map_subscribe_transient_local", bool, True, "the map is always read transient-local"),
), ("nav2_costmap_2d::StaticLayer",))

OBSTACLE_LAYER = Section("<costmap>.<obstacle layer>", (
    _plugin(),
    core(CostmapConfig, "obstacle_layer", key="enabled"),
    own("observation_sources", str, "", "space-separated source section names"),
), ("nav2_costmap_2d::ObstacleLayer",), nested=True)

OBSERVATION_SOURCE = Section("<obstacle layer>.<source>", (
    own("topic", str | None, "", "scan topic; empty (no lidar on this deploy) disables the source"),
    own("data_type", str, "LaserScan", "message type", choices=("LaserScan",)),
    *core_all(ObservationSource),
    compat("max_obstacle_height", float, 2.0, "a planar scan has no height"),
))

INFLATION_LAYER = Section("<costmap>.<inflation layer>", (
    _plugin(),
    core(CostmapConfig, "inflation_layer", key="enabled"),
    *(core(CostmapConfig, n) for n in ("inflation_radius", "cost_scaling_factor", "inflate_unknown")),
), ("nav2_costmap_2d::InflationLayer",))

LAYERS = {"nav2_costmap_2d::StaticLayer": STATIC_LAYER, "nav2_costmap_2d::ObstacleLayer": OBSTACLE_LAYER,
          "nav2_costmap_2d::InflationLayer": INFLATION_LAYER}

BEHAVIOR_SERVER = Section("behavior_server", (
    _sim_time(),
    own("behavior_plugins", list[str], ["spin", "backup", "wait"], "behaviour section names"),
    compat("cycle_frequency", float, 10.0, "behaviours step at the controller rate"),
    *(core(RecoveryConfig, n) for n in ("simulate_ahead_time", "max_rotational_vel", "min_rotational_vel",
                                        "rotational_acc_lim", "time_allowance")),
    *(core(RecoveryConfig, n) for n in ("escape_dist", "escape_turn", "escape_directions", "escape_speed",
                                        "escape_margin", "escape_enough", "escape_tolerance", "escape_reach")),
), nested=True)

BEHAVIORS = {"nav2_behaviors/Spin": "spin", "nav2_behaviors/BackUp": "backup", "nav2_behaviors/Wait": "wait",
             "robonix_nav/Escape": "escape"}
BEHAVIOR = Section("behavior_server.<behavior>", (_plugin(),), tuple(BEHAVIORS))

#: Every table, in the order the reference lists them.
#: The critic sections as the reference shows them (each critic's own default weight is in the MPPI table).
CRITIC_REFERENCE = Section("<MPPI controller>.<critic>", (
    own("enabled", bool, True, "false switches this critic off"),
    own("cost_weight", float | None, None, "the critic's weight; default: the MppiConfig weight it sets", ge=0),
    own("threshold_to_consider", float | None, None, "GoalCritic only: sets goal_distance", gt=0),
    own("progress_weight", float | None, None, "PathFollowCritic only: sets progress_weight", ge=0),
    compat("cost_power", int, 1, "costs enter linearly"),
), doc="Critic sections, by Nav2 name, and the weight their cost_weight sets: CostCritic and ObstaclesCritic → "
       "cost_weight; GoalCritic → goal_weight; GoalAngleCritic and PathAngleCritic → heading_weight; "
       "PathAlignCritic → path_align_weight; PathFollowCritic → path_follow_weight; TwirlingCritic → "
       "twirling_weight; SmoothnessCritic (ours) → smoothness_weight. ConstraintCritic and PreferForwardCritic "
       "are accepted: the sampler enforces the limits and either end of the body may lead.")

SECTIONS = (BT_NAVIGATOR, PLANNER_SERVER, PLANNER, CONTROLLER_SERVER, CONTROLLER, MPPI_CONTROLLER,
            CRITIC_REFERENCE, SIMPLE_GOAL_CHECKER,
            STOPPED_GOAL_CHECKER, PROGRESS_CHECKER, COSTMAP, STATIC_LAYER, OBSTACLE_LAYER, OBSERVATION_SOURCE,
            INFLATION_LAYER, BEHAVIOR_SERVER, BEHAVIOR)
