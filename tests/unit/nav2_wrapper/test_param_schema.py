"""One declaration per parameter: the core fields' declarations drive validation, the configs and the doc."""

from __future__ import annotations

import dataclasses

import pytest

from nav2_wrapper import paramdoc
from nav2_wrapper import params_schema as ps
from nav2_wrapper.core import (
    ControllerConfig,
    CostmapConfig,
    GoalCheckerConfig,
    NavigatorConfig,
    ObservationSource,
    PlannerConfig,
    ProgressCheckerConfig,
    RecoveryConfig,
)
from nav2_wrapper.params import ParamsError, load_params, profile_path
from nav2_wrapper.robot_io import RobotDescriptionError, RobotLimits, load_robot
from robonix_common.params import declared

CONFIGS = (ControllerConfig, CostmapConfig, GoalCheckerConfig, NavigatorConfig, ObservationSource, PlannerConfig,
           ProgressCheckerConfig, RecoveryConfig)

MINIMAL = """
planner_server:
  ros__parameters:
    GridBased: {plugin: robonix_nav/CostAwareAStar}
controller_server:
  ros__parameters:
    FollowPath: {plugin: "robonix_nav::HolonomicPursuitController"}
    general_goal_checker: {plugin: "nav2_controller::SimpleGoalChecker"}
    progress_checker: {plugin: "nav2_controller::SimpleProgressChecker"}
behavior_server:
  ros__parameters:
    spin: {plugin: nav2_behaviors/Spin}
    backup: {plugin: nav2_behaviors/BackUp}
    wait: {plugin: nav2_behaviors/Wait}
"""


def test_capability_reference_is_generated_and_current() -> None:
    """CAPABILITY.md carries the rendered tables; run ``python -m nav2_wrapper.paramdoc --write`` when this fails."""
    text = paramdoc.CAPABILITY_MD.read_text()
    assert paramdoc.BEGIN in text
    assert paramdoc.splice(text, paramdoc.render()) == text
    assert paramdoc.main(["--check"]) == 0


def test_stale_reference_is_detected() -> None:
    text = paramdoc.CAPABILITY_MD.read_text().replace("| `sim_dt` |", "| `sim_step` |")
    assert paramdoc.splice(text, paramdoc.render()) != text


def test_every_core_parameter_is_settable_from_yaml() -> None:
    targeted = {(k.target, k.field) for sec in ps.SECTIONS for k in sec.keys if k.target is not None}
    missing = [f"{cls.__name__}.{name}" for cls in CONFIGS for name in declared(cls) if (cls, name) not in targeted]
    assert missing == []
    for name in ("dense_time", "sim_dt", "footprint_check_resolution"):
        assert ps.CONTROLLER.get(name) is not None


def test_a_file_without_values_builds_the_declared_defaults() -> None:
    """Defaults live only on the core fields: a params file that sets nothing yields exactly them."""
    lp = load_params("x.yml", text=MINIMAL, scan_topic="")
    cfg = lp.config
    for part, cls in ((cfg.planner, PlannerConfig), (cfg.goal_checker, GoalCheckerConfig),
                      (cfg.progress_checker, ProgressCheckerConfig), (cfg.recovery, RecoveryConfig),
                      (cfg.navigator, NavigatorConfig)):
        assert part == cls()
    fp = cfg.controller.footprint
    assert cfg.controller == ControllerConfig(footprint=fp)
    assert not cfg.goal_checker.stopped
    assert lp.warnings == []
    assert lp.unused == []


def test_hidden_controller_parameters_are_read_and_range_checked() -> None:
    text = profile_path("sim").read_text().replace(
        "      collision_check_time: 1.0\n",
        "      collision_check_time: 1.0\n      dense_time: 0.4\n      sim_dt: 0.05\n"
        "      footprint_check_resolution: 0.1\n")
    c = load_params("sim", text=text).config.controller
    assert (c.dense_time, c.sim_dt, c.footprint_check_resolution) == (0.4, 0.05, 0.1)
    bad = text.replace("sim_dt: 0.05", "sim_dt: 0")
    with pytest.raises(ParamsError, match=r"controller_server\.ros__parameters\.FollowPath\.sim_dt: must be > 0"):
        load_params("sim", text=bad)


def test_wrong_types_name_the_key() -> None:
    text = profile_path("sim").read_text()
    with pytest.raises(ParamsError, match=r"general_goal_checker\.stateful: must be true or false"):
        load_params("sim", text=text.replace("stateful: true", "stateful: 3"))
    with pytest.raises(ParamsError, match=r"GridBased\.unknown_cost: must be an integer"):
        load_params("sim", text=text.replace("unknown_cost: 200", "unknown_cost: 20.5"))
    with pytest.raises(ParamsError, match=r"recovery_behaviors: 'dance' is not one of"):
        load_params("sim", text=text.replace("[escape, clear_costmaps, spin, wait, backup]", "[spin, dance]"))


def test_unknown_keys_warn_and_compat_keys_are_listed() -> None:
    text = profile_path("sim").read_text().replace(
        "    replan_frequency: 1.0", "    replan_frequency: 1.0\n    bt_loop_duration: 10\n")
    lp = load_params("sim", text=text)
    assert any("bt_navigator.ros__parameters.bt_loop_duration" in w and "ignored" in w for w in lp.warnings)
    assert "local_costmap.local_costmap.ros__parameters.update_frequency" in lp.unused
    assert "behavior_server.ros__parameters.cycle_frequency" in lp.unused
    assert not any("update_frequency" in w for w in lp.warnings)
    nested = profile_path("sim").read_text().replace("      tolerance: 0.25\n",
                                                     "      tolerance: 0.25\n      search: {depth: 3}\n")
    assert any("GridBased.search.depth" in w for w in load_params("sim", text=nested).warnings)
    with pytest.raises(ParamsError, match="update_frequency: must be a number"):
        load_params("sim", text=text.replace("update_frequency: 10.0", "update_frequency: fast"))


def test_controller_limits_above_the_robot_are_warned() -> None:
    robot = load_robot()
    assert robot.limits is not None
    assert load_params("sim", limits=robot.limits).warnings == []
    slow = dataclasses.replace(robot.limits, max_vx=0.3)
    lp = load_params("sim", limits=slow)
    assert any("FollowPath.max_vel_x" in w and "limits.max_vx" in w for w in lp.warnings)
    assert isinstance(slow, RobotLimits)


def test_robot_description_errors_name_the_key(tmp_path) -> None:
    p = tmp_path / "r.yaml"
    p.write_text("name: x\nfootprint: [[0, 0], [1, 0]]\n")
    with pytest.raises(RobotDescriptionError, match="footprint: footprint needs at least 3 points"):
        load_robot(p)
    p.write_text("footprint: [[0.3, 0.2], [-0.3, 0.2], [-0.3, -0.2]]\nlimits: {max_vx: -1}\n")
    with pytest.raises(RobotDescriptionError, match=r"limits\.max_vx: must be a positive number"):
        load_robot(p)
