"""Navigation core: costmaps, planner, controller, checkers, recoveries, navigator.

Imports only numpy/scipy/numba and robonix_common (a test enforces it); robot description and params files
are read by ``nav2_wrapper.robot_io`` and ``nav2_wrapper.params``, which pass the results in.

A reader's map (read in this order):

- ``interfaces``: the Protocols every component is used through (GlobalPlanner, Controller, Critic,
  Recovery) and the data they exchange; start here.
- ``navigator``: the state machine of one goal: plan, follow, replan, check progress, recover.
- ``costs``, ``costmap``, ``footprint``: cost values, the layered costmap (static, obstacle, inflation).
- ``planner``: the 2D global planner (goal tolerance, escape from the inflation band, Theta*-style
  shortcut); its search is ``_search.astar``, one numba kernel: one bucket queue, one expansion loop, one
  move table, its invariants in ``_search``'s docstring. ``reference``: a textbook A* over the same move
  model, that tests and the benchmark check every plan against.
- ``se2_planner`` (+ ``_se2_search``, ``footprint_planning``, ``headings``): the footprint-aware (x, y,
  heading) fallback for passages the round 2D model calls blocked.
- ``controller``: the pursuit controller (also the safety check and escape move MPPI falls back to);
  ``mppi`` (+ ``_mppi_kernels``): the sampling controller; ``critics``: its critics, one class each.
- ``checkers`` (goal, progress), ``recoveries`` (spin, back up, wait, clear, escape), ``escape``,
  ``grace``, ``latency``: the navigator's helpers.
- ``warmup``: compiles (or loads from the cache) every numba kernel a navigation process uses, once, in the
  background; ``compile_kernels()`` / ``compile_in_background()`` are its entry points.
"""

from robonix_common import jit_setup  # noqa: F401  (first: numba's cache dir, before any kernel)

from .checkers import GoalChecker, GoalCheckerConfig, ProgressChecker, ProgressCheckerConfig
from .controller import ControllerConfig, ControlOutput, HolonomicController
from .costmap import Costmap, CostmapConfig, ObservationSource, Scan
from .costs import FREE, INSCRIBED, LETHAL, NO_INFORMATION, inflation_cost
from .footprint import Footprint
from .navigator import Command, GoalRecord, NavConfig, Navigator, NavigatorConfig, validate_goal
from .planner import GlobalPlanner, PlannerConfig, PlanResult
from .recoveries import RecoveryConfig, RecoverySequence

__all__ = [
    "FREE", "INSCRIBED", "LETHAL", "NO_INFORMATION", "Command", "ControlOutput", "ControllerConfig", "Costmap",
    "CostmapConfig", "Footprint", "GlobalPlanner", "GoalChecker", "GoalCheckerConfig", "GoalRecord",
    "HolonomicController", "NavConfig", "Navigator", "NavigatorConfig", "ObservationSource",
    "PlanResult", "PlannerConfig", "ProgressChecker", "ProgressCheckerConfig", "Scan", "RecoveryConfig",
    "RecoverySequence", "inflation_cost", "validate_goal",
]
