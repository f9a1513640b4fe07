"""Params profiles: all validate, tokens fill, unfilled token is an error, unread parameters warn."""

import pytest

from nav2_wrapper.core import Footprint
from nav2_wrapper.params import PROFILES, ParamsError, fill_tokens, load_params, profile_path


@pytest.mark.parametrize("profile", PROFILES)
def test_profiles_validate_without_warnings(profile):
    lp = load_params(profile, map_topic="/robonix/map", odom_topic="/odom2", scan_topic="/scan_f")
    assert lp.warnings == []
    assert lp.topics == {"map": "/robonix/map", "odom": "/odom2", "scan": "/scan_f"}
    cfg = lp.config
    assert cfg.global_costmap.static_layer
    assert cfg.global_costmap.inflation_layer
    assert cfg.global_costmap.footprint.inscribed_radius == pytest.approx(0.25)
    assert cfg.local_costmap.rolling_window
    assert cfg.progress_checker.required_movement_radius == 0.5


def test_profile_meanings():
    sim, slam, dflt = (load_params(p).config for p in ("sim", "slam", "default"))
    assert sim.planner.allow_unknown
    assert not slam.planner.allow_unknown
    assert not dflt.planner.allow_unknown
    assert sim.goal_checker.xy_goal_tolerance == 0.25
    assert sim.navigator.controller_frequency == 20.0
    assert slam.controller.max_vel_x < sim.controller.max_vel_x
    assert slam.goal_checker.xy_goal_tolerance > sim.goal_checker.xy_goal_tolerance
    assert sim.navigator.global_frame == "map"


def test_footprint_token_takes_the_robot_description():
    fp = Footprint([[0.5, 0.3], [-0.5, 0.3], [-0.5, -0.3], [0.5, -0.3]])
    lp = load_params("sim", footprint=fp)
    assert lp.config.global_costmap.footprint.inscribed_radius == pytest.approx(0.3)
    assert lp.config.controller.footprint.circumscribed_radius == pytest.approx((0.5**2 + 0.3**2) ** 0.5)


def test_unfilled_token_is_an_error_naming_it():
    with pytest.raises(ParamsError, match="__ROBONIX_SCAN_TOPIC__"):
        fill_tokens("topic: __ROBONIX_SCAN_TOPIC__", {"__ROBONIX_MAP_TOPIC__": "/map"})
    text = profile_path("sim").read_text().replace("__ROBONIX_MAP_TOPIC__", "__ROBONIX_MAPP_TOPIC__")
    with pytest.raises(ParamsError, match="__ROBONIX_MAPP_TOPIC__"):
        load_params("sim", text=text)


def test_unused_parameter_and_unselected_plugin_warn():
    text = profile_path("sim").read_text()
    text = text.replace("      tolerance: 0.25\n", "      tolerance: 0.25\n      use_astar: true\n")
    text = text.replace("    FollowPath:\n", "    DWB:\n      max_vel_x: 0.26\n    FollowPath:\n")
    lp = load_params("sim", text=text)
    joined = "\n".join(lp.warnings)
    assert "planner_server.ros__parameters.GridBased.use_astar" in joined
    assert "controller_server.ros__parameters.DWB.max_vel_x" in joined
    assert "unselected" in joined


def test_bad_values_and_plugins_are_errors():
    text = profile_path("sim").read_text()
    with pytest.raises(ParamsError, match="inflation_radius"):
        load_params("sim", text=text.replace("inflation_radius: 0.55", "inflation_radius: -1", 1))
    with pytest.raises(ParamsError, match="VoxelLayer"):
        load_params("sim", text=text.replace('"nav2_costmap_2d::ObstacleLayer"', '"nav2_costmap_2d::VoxelLayer"', 1))
    with pytest.raises(ParamsError, match="unknown params_profile"):
        profile_path("fast")


def test_missing_scan_disables_obstacle_layer_with_warning():
    lp = load_params("sim", scan_topic="")
    assert not lp.config.global_costmap.obstacle_layer
    assert any("scan.topic" in w for w in lp.warnings)


def _with_planner(plugin: str, smooth: str = "true") -> str:
    text = profile_path("sim").read_text()
    assert 'plugin: "robonix_nav/CostAwareAStar"' in text
    assert "smooth_path: true" in text
    text = text.replace("smooth_path: true", f"smooth_path: {smooth}", 1)
    return text.replace('plugin: "robonix_nav/CostAwareAStar"', f'plugin: "{plugin}"', 1)


def test_planner_plugin_names_pick_the_path_style_or_are_refused():
    """SmacPlanner2D returns the 8-connected grid path, ThetaStarPlanner an any-angle one (whatever smooth_path
    says, with a warning when it says otherwise); NavfnPlanner is refused naming what we provide."""
    smac = load_params("sim", text=_with_planner("nav2_smac_planner/SmacPlanner2D"))
    assert smac.config.planner.smooth_path is False
    theta = load_params("sim", text=_with_planner("nav2_theta_star_planner/ThetaStarPlanner", "false"))
    assert theta.config.planner.smooth_path is True
    assert any("smooth_path" in w and "ThetaStarPlanner" in w for w in theta.warnings)
    assert load_params("sim").config.planner.smooth_path is True
    with pytest.raises(ParamsError, match="NavFn.*CostAwareAStar.*SmacPlanner2D.*ThetaStarPlanner"):
        load_params("sim", text=_with_planner("nav2_navfn_planner/NavfnPlanner"))
