"""The in-memory snapshot of a SLAM session: the pose graph plus every node's scan, so mapping can continue.

The core only builds and consumes this snapshot; reading and writing it as a file is
:mod:`slam_service.session_io`'s job, so the core never touches a file format.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from .posegraph import PoseGraph
from .types import SlamConfig


@dataclass
class SessionData:
    """Everything :meth:`SlamEngine.load` needs to continue mapping where a run stopped."""

    graph: PoseGraph
    odom: NDArray[np.float64]  # (N, 3) odometry pose at each node
    stamps: NDArray[np.float64]  # (N,)
    path_dist: NDArray[np.float64]  # (N,) distance travelled along the chain
    points: list[NDArray[np.float32]] = field(default_factory=list)  # per node, base frame (P, 2)
    origins: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 2)))  # lidar position, base
    config: SlamConfig = field(default_factory=SlamConfig)
    # node -> base-frame ends of its no-return beams' free stretches ((F, 2), only nodes that have any):
    # part of what a node draws into the map, so a reloaded session must have them to draw the same map
    free: dict[int, NDArray[np.float32]] = field(default_factory=dict)
