"""Navigation core: costmaps, planner, controller, checkers, recoveries, navigator. numpy/scipy/numba only."""

from .checkers import GoalChecker, GoalCheckerConfig, ProgressChecker, ProgressCheckerConfig
from .controller import ControllerConfig, ControlOutput, HolonomicController
from .costmap import Costmap, CostmapConfig, LaserScan, ObservationSource
from .costs import FREE, INSCRIBED, LETHAL, NO_INFORMATION, inflation_cost
from .footprint import Footprint
from .navigator import Command, GoalRecord, NavConfig, Navigator, NavigatorConfig, validate_goal
from .planner import GlobalPlanner, PlannerConfig, PlanResult
from .recoveries import RecoveryConfig, RecoverySequence

__all__ = [
    "FREE", "INSCRIBED", "LETHAL", "NO_INFORMATION", "Command", "ControlOutput", "ControllerConfig", "Costmap",
    "CostmapConfig", "Footprint", "GlobalPlanner", "GoalChecker", "GoalCheckerConfig", "GoalRecord",
    "HolonomicController", "LaserScan", "NavConfig", "Navigator", "NavigatorConfig", "ObservationSource",
    "PlanResult", "PlannerConfig", "ProgressChecker", "ProgressCheckerConfig", "RecoveryConfig",
    "RecoverySequence", "inflation_cost", "validate_goal",
]
