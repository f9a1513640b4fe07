"""The core's components satisfy the interfaces others use them through, and MPPI critics compose from config."""

from __future__ import annotations

import numpy as np

from nav2_wrapper.core import ControllerConfig, GlobalPlanner, HolonomicController, RecoveryConfig, interfaces
from nav2_wrapper.core.critics import build_critics
from nav2_wrapper.core.mppi import MppiConfig, MppiController
from nav2_wrapper.core.recoveries import BackUp, Spin
from nav2_wrapper.robot_io import load_footprint


def test_components_satisfy_their_protocols() -> None:
    fp = load_footprint()
    assert isinstance(GlobalPlanner(), interfaces.GlobalPlanner)
    for ctrl in (HolonomicController(ControllerConfig(footprint=fp)), MppiController(ControllerConfig(footprint=fp))):
        assert isinstance(ctrl, interfaces.Controller)
    for behaviour in (Spin(RecoveryConfig()), BackUp(RecoveryConfig())):
        assert isinstance(behaviour, interfaces.Recovery)
    for critic in MppiController(ControllerConfig(footprint=fp)).critics:
        assert isinstance(critic, interfaces.Critic)


def test_the_followed_path_is_public_and_index_ahead_walks_it() -> None:
    ctrl = HolonomicController(ControllerConfig(footprint=load_footprint()))
    ctrl.set_path(np.stack([np.linspace(0.0, 2.0, 41), np.zeros(41)], axis=1))
    assert ctrl.path_cum[-1] == 2.0
    assert ctrl.progress_index == -1
    assert ctrl.index_ahead(0, 0.5) == 10
    assert ctrl.index_ahead(30, 5.0) == 40        # clamped to the last point
    ctrl.remaining((1.0, 0.02, 0.0))
    assert ctrl.progress_index == 20


def test_critics_with_zero_weight_are_not_built_and_collision_always_is() -> None:
    pts = np.zeros((4, 2))
    names = [c.name for c in build_critics(MppiConfig(), pts, pts)]
    assert names[0] == "CollisionCritic"
    assert {"CostCritic", "GoalCritic", "PathCritic", "HeadingCritic", "TwirlingCritic",
            "SmoothnessCritic"} <= set(names)
    few = build_critics(MppiConfig(twirling_weight=0.0, smoothness_weight=0.0, cost_weight=0.0), pts, pts)
    assert [c.name for c in few] == ["CollisionCritic", "GoalCritic", "PathCritic", "HeadingCritic"]
