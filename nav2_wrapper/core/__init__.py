"""Navigation core: costmaps, planner, controller, checkers, recoveries, navigator.

Imports only numpy/scipy/numba and robonix_common (a test enforces it); robot description and params files
are read by ``nav2_wrapper.robot_io`` and ``nav2_wrapper.params``, which pass the results in.
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
