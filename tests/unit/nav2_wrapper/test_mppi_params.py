"""Selecting the MPPI controller from a Nav2 params file, in Nav2's MPPI shape."""

from __future__ import annotations

import re

import pytest

from nav2_wrapper.core.controller import HolonomicController
from nav2_wrapper.core.mppi import MppiController
from nav2_wrapper.core.navigator import Navigator
from nav2_wrapper.params import ParamsError, load_params, profile_path

MPPI_BLOCK = """    FollowPath:
      plugin: "nav2_mppi_controller::MPPIController"
      motion_model: "Omni"
      batch_size: 800
      time_steps: 40
      model_dt: 0.05
      vx_std: 0.25
      vy_std: 0.2
      wz_std: 0.4
      vx_max: 0.45
      vy_max: 0.4
      wz_max: 1.5
      vx_min: -0.45
      iteration_count: 1
      temperature: 0.3
      critics: ["ConstraintCritic", "CostCritic", "GoalCritic", "PathAlignCritic", "PathFollowCritic"]
      CostCritic:
        enabled: true
        cost_power: 1
        cost_weight: 3.81
      GoalCritic:
        cost_weight: 6.0
        threshold_to_consider: 1.4
      PathAlignCritic:
        enabled: false
        cost_weight: 14.0
      TwirlingCritic:
        cost_weight: 0.5
"""


def _with_controller(block: str) -> str:
    text = profile_path("sim").read_text()
    return re.sub(r"    FollowPath:\n(?:      .*\n)+", block, text, count=1)


def test_mppi_section_builds_the_mppi_controller() -> None:
    loaded = load_params("sim", text=_with_controller(MPPI_BLOCK))
    cfg = loaded.config
    assert cfg.mppi is not None
    m, c = cfg.mppi, cfg.controller
    assert (m.batch_size, m.time_steps, m.vx_std) == (800, 40, 0.25)
    assert (c.max_vel_x, c.max_vel_y, c.max_vel_theta) == (0.45, 0.4, 1.5)      # Nav2 MPPI's limit names
    assert m.cost_weight == 3.81
    assert (m.goal_weight, m.goal_distance) == (6.0, 1.4)
    assert m.path_align_weight == 0.0          # listed but enabled: false
    assert m.twirling_weight == 0.0            # section present but the critic is not listed
    assert m.heading_weight == 0.0             # neither angle critic listed
    assert m.path_follow_weight > 0
    assert m.collision_cost > 0
    assert any(w.endswith("FollowPath.TwirlingCritic.cost_weight' is under an unselected plugin and is not read")
               for w in loaded.warnings)
    assert any(u.endswith("FollowPath.vx_min") for u in loaded.unused)
    assert isinstance(Navigator(cfg).controller, MppiController)


PURSUIT_BLOCK = """    FollowPath:
      plugin: "robonix_nav::HolonomicPursuitController"
      max_vel_x: 0.4
      max_vel_theta: 1.2
      desired_linear_vel: 0.4
"""


@pytest.mark.parametrize("profile", ["sim", "slam", "default"])
def test_mppi_is_the_profiles_controller(profile: str) -> None:
    loaded = load_params(profile)
    cfg = loaded.config
    assert cfg.mppi is not None
    assert isinstance(Navigator(cfg).controller, MppiController)
    assert not loaded.warnings
    assert not any(".FollowPath." in u for u in loaded.unused)      # every controller key is read
    # the profile's limits reach the controller under MPPI's names (vx_max ... az_max)
    assert cfg.controller.max_vel_x == cfg.controller.desired_linear_vel


def test_pursuit_stays_selectable() -> None:
    cfg = load_params("sim", text=_with_controller(PURSUIT_BLOCK)).config
    assert cfg.mppi is None
    controller = Navigator(cfg).controller
    assert isinstance(controller, HolonomicController)
    assert not isinstance(controller, MppiController)
    assert (cfg.controller.max_vel_x, cfg.controller.max_vel_theta) == (0.4, 1.2)


@pytest.mark.parametrize(("old", "new", "needle"), [
    ("      batch_size: 800\n", "      batch_size: 4\n", "FollowPath.batch_size: must be >= 16"),
    ('      motion_model: "Omni"\n', '      motion_model: "DiffDrive"\n',
     "FollowPath.motion_model: 'DiffDrive' is not one of Omni"),
    ("      critics: [", '      critics: ["VelocityDeadbandCritic", ',
     "FollowPath.critics: unsupported critic(s) VelocityDeadbandCritic"),
])
def test_bad_mppi_values_name_the_key(old: str, new: str, needle: str) -> None:
    assert old in MPPI_BLOCK
    with pytest.raises(ParamsError, match=re.escape(needle)):
        load_params("sim", text=_with_controller(MPPI_BLOCK.replace(old, new)))
