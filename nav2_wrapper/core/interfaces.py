"""The navigation core's component interfaces, after Nav2's plugin types: what a global planner, a controller,
an MPPI critic and a recovery behaviour offer, and the data they exchange as public fields.

Why: the navigator, the recoveries and the SE(2) fallback used to read each other's private state (the
controller's cumulative path length and progress index, the planner's path extraction). Each of those is
now a public field or method declared here, so a component can be replaced by anything with the same shape
(``typing.Protocol``: structural, no base class to inherit), and a reader sees what flows between them:

- a plan is a ``PlanResult``: dense world points, per-point headings when the SE(2) fallback planned it, the
  grid path and its cost;
- the followed path is the controller's ``path`` with ``path_cum`` (metres along it, per point) and
  ``progress_index`` (the point nearest the base at the last step), and ``index_ahead`` to look along it;
- a critic scores K sampled trajectories from one ``CriticInput`` and returns K costs;
- a recovery behaviour is started, then stepped until its ``Step`` says done.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    from .controller import ControlOutput
    from .costmap import Costmap
    from .critics import CriticInput
    from .planner import PlanResult
    from .recoveries import Step

Pose2D = tuple[float, float, float]


@runtime_checkable
class GlobalPlanner(Protocol):
    """Plans a path on a costmap (Nav2's GlobalPlanner): world (x, y) start and goal in the costmap frame."""

    def plan(self, costmap: Costmap, start: tuple[float, float], goal: tuple[float, float]) -> PlanResult: ...


@runtime_checkable
class Controller(Protocol):
    """Follows a path (Nav2's Controller). ``path``, ``path_cum`` and ``progress_index`` are public so the
    navigator and recoveries look along the followed path without knowing the controller's type."""

    path: NDArray[np.float64]            # (N, 2) world points being followed
    path_cum: NDArray[np.float64]        # (N,) metres along the path at each point
    progress_index: int                  # point nearest the base at the last step; -1 before the first
    speed_limit: float                   # fraction of the max velocities

    def set_path(self, path: NDArray[np.float64], headings: NDArray[np.float64] | None = None) -> None: ...

    def set_speed_limit(self, limit: float, percentage: bool = True) -> None: ...

    def index_ahead(self, i: int, distance: float) -> int: ...

    def remaining(self, pose: Pose2D) -> float: ...

    def compute(self, pose: Pose2D, vel: tuple[float, float, float], goal: Pose2D, costmap: Costmap, dt: float,
                xy_reached: bool = False) -> ControlOutput: ...


@runtime_checkable
class Critic(Protocol):
    """One term of the MPPI objective (Nav2 MPPI's critic plugin): K trajectory costs, lower is better."""

    name: str

    def score(self, inp: CriticInput) -> NDArray[np.float64]: ...


@runtime_checkable
class Recovery(Protocol):
    """A recovery behaviour (Nav2's Behavior): started once, then stepped until its Step says done."""

    name: str

    def start(self, now: float, pose: Pose2D) -> None: ...

    def step(self, now: float, pose: Pose2D, costmap: Costmap, ctrl: Controller) -> Step: ...
