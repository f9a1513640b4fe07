"""MPPI critics, one class each (after Nav2 MPPI's critic plugins), and the table that builds them from config.

Each critic scores the K sampled trajectories of one control step from the same ``CriticInput`` and returns K
costs (lower is better); the controller sums them. A critic whose weight is 0 (its section not listed in the
params profile sets it so) is not built. The collision critic is always on.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from robonix_common.geometry import Pose2D, wrap_angle

from .costmap import Costmap
from .costs import INSCRIBED, LETHAL, NO_INFORMATION, inflation_cost

if TYPE_CHECKING:
    from .interfaces import Critic
    from .mppi import MppiConfig


@dataclass
class CriticInput:
    """What every critic may read at one control step."""

    pose: Pose2D                        # where the command will act (costmap frame)
    goal: Pose2D
    costmap: Costmap                    # the local costmap
    traj: NDArray[np.float64]           # (K, T, 3) sampled poses
    u: NDArray[np.float64]              # (K, T, 3) sampled controls
    path: NDArray[np.float64]           # (N, 2) followed path
    path_cum: NDArray[np.float64]       # (N,) metres along it
    index: int                          # path point nearest the base
    horizon: float                      # metres the horizon covers at the desired speed
    heading_target: float               # yaw the heading critic pulls toward (rad)
    heading_gain: float = 1.0           # its weight multiplier (the passage-fitting yaw raises it)

    def goal_distance(self) -> float:
        return math.hypot(self.goal[0] - self.pose[0], self.goal[1] - self.pose[1])


class CollisionCritic:
    """Footprint contacts (``collision_cost`` per trajectory that touches a lethal cell the robot does not
    already touch) plus the clearance band (``clearance_weight`` × share of poses whose grown footprint
    touches one).

    Why the second: the centre's cost cannot tell a body lined up with a doorway from one entering it
    skewed (same centre, corners 10 cm nearer the jambs), and a collision test with no margin lets the
    corners graze. A margin band rather than the inscribed-cost share of the outline: in a 0.8 m gap the
    whole 0.5 m body is within the inscribed radius of both posts, so a share of inscribed cells charges
    every way through and the robot stalls; the margin band is empty there and charges only real near
    misses. It is a preference, bounded by its weight, never a ban.

    Off by default, because the trade-off measured so far goes the wrong way in dense clutter. At weight 20,
    in-process on the four built-in scenes (nominal and noisy lidar) the closest approach went from 5.0 to
    9.0 cm and 40/40 stayed 40/40; the 0.8 m gap beside a dropped box from 3.5 to 6.2–7.9 cm. But on the
    clutter worlds whose passages have only the proof's 5 cm, forward samples through them are all charged,
    stopping is not, and the robot stalled: clutter worlds 2, 8 and 14 went from 6/6 to 3/6 (weight 8 too, and
    with the critic off on heading-planned SE(2) paths); charged relative to the best sample going forward,
    1/6.
    """

    name = "CollisionCritic"

    def __init__(self, collision_cost: float, clearance_weight: float, clearance_margin: float, stride: int,
                 sample_points: NDArray[np.float64], margin_points: NDArray[np.float64]) -> None:
        self.collision_cost, self.clearance_weight, self.clearance_margin = collision_cost, clearance_weight, \
            clearance_margin
        self.stride = max(1, stride)
        self.sample_points, self.margin_points = sample_points, margin_points

    def score(self, inp: CriticInput) -> NDArray[np.float64]:
        hits, close = self.contacts(inp.pose, inp.traj, inp.costmap)
        return self.collision_cost * hits + self.clearance_weight * close

    def contacts(self, pose: Pose2D, traj: NDArray[np.float64],
                 costmap: Costmap) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Per trajectory: 1.0 if it makes a new contact, else 0; and the share of its checked poses in the
        clearance band."""
        sub = traj[:, self.stride - 1::self.stride]
        k, t = sub.shape[:2]
        poses = sub.reshape(-1, 3)
        centre = costmap.cost_at(poses[:, 0], poses[:, 1], outside=0)
        known = centre != NO_INFORMATION
        close = np.zeros(len(poses), dtype=bool)
        if self.clearance_weight > 0 and self.clearance_margin > 0:
            band = (centre >= possible_collision_cost(costmap, self.clearance_margin)) & known
            if band.any():
                close[band] = (costmap.footprint_costs(poses[band], self.margin_points, outside=0) == LETHAL).any(
                    axis=1)
        near = (centre >= possible_collision_cost(costmap)) & known
        hit = np.zeros(len(poses), dtype=bool)
        if near.any():
            fc = costmap.footprint_costs(poses[near], self.sample_points, outside=0)
            lethal = fc == LETHAL
            if lethal.any():
                start = costmap.footprint_costs(np.array([pose], dtype=float), self.sample_points, outside=0)
                if (start == LETHAL).any():   # already touching: count only clearly deeper contacts
                    lethal &= (costmap.cost_at(poses[near, 0], poses[near, 1], outside=0) >= INSCRIBED)[:, None]
            hit[near] = lethal.any(axis=1)
        return hit.reshape(k, t).any(axis=1).astype(float), close.reshape(k, t).mean(axis=1)


def possible_collision_cost(costmap: Costmap, grow: float = 0.0) -> int:
    """Centre cost below which no point of the footprint grown by ``grow`` can touch a lethal cell (the
    circumscribed radius plus ``grow``; 1 if that lies beyond the inflation, where the cost says nothing)."""
    fp = costmap.cfg.footprint
    reach = fp.circumscribed_radius + grow
    if reach >= costmap.cfg.inflation_radius:
        return 1
    val = int(inflation_cost(reach, fp.inscribed_radius, costmap.cfg.inflation_radius,
                             costmap.cfg.cost_scaling_factor))
    return max(1, val)


class CostCritic:
    """Mean costmap cost under the trajectory's centre (unknown counts as free), scaled to 0..1."""

    name = "CostCritic"

    def __init__(self, weight: float) -> None:
        self.weight = weight

    def score(self, inp: CriticInput) -> NDArray[np.float64]:
        c = inp.costmap.cost_at(inp.traj[..., 0], inp.traj[..., 1], outside=0).astype(float)
        c[c == NO_INFORMATION] = 0.0
        return self.weight * np.minimum(c, INSCRIBED).mean(axis=1) / INSCRIBED


class GoalCritic:
    """Within ``goal_distance`` of the goal: the trajectory's mean distance to it."""

    name = "GoalCritic"

    def __init__(self, weight: float, goal_distance: float) -> None:
        self.weight, self.goal_distance = weight, goal_distance

    def score(self, inp: CriticInput) -> NDArray[np.float64]:
        if inp.goal_distance() >= self.goal_distance:
            return np.zeros(len(inp.traj))
        t = inp.traj
        return self.weight * np.hypot(t[..., 0] - inp.goal[0], t[..., 1] - inp.goal[1]).mean(axis=1)


class PathCritic:
    """Farther than ``goal_distance`` from the goal: follow (end point toward the point the horizon should
    reach), align (stay near the path) and progress (arc length gained), all against the path ahead.

    The path ahead is rasterised on the local costmap's grid and a distance transform gives, for every cell,
    the distance to the path and the arc length of its nearest path point: each trajectory pose is then two
    array lookups, whatever the number of samples."""

    name = "PathCritic"

    def __init__(self, follow: float, align: float, progress: float, goal_distance: float) -> None:
        self.follow, self.align, self.progress, self.goal_distance = follow, align, progress, goal_distance

    def score(self, inp: CriticInput) -> NDArray[np.float64]:
        if inp.goal_distance() < self.goal_distance:
            return np.zeros(len(inp.traj))
        i, traj, costmap = inp.index, inp.traj, inp.costmap
        j_end = int(np.searchsorted(inp.path_cum, inp.path_cum[i] + inp.horizon + 0.5)) + 1
        ahead = inp.path[i:j_end]
        cum = inp.path_cum[i:j_end] - inp.path_cum[i]
        dist, arc = path_field(ahead, cum, costmap)
        col, row = costmap.world_to_cell(traj[..., 0], traj[..., 1])
        rows, cols = dist.shape
        np.clip(col, 0, cols - 1, out=col)
        np.clip(row, 0, rows - 1, out=row)
        align = dist[row, col].mean(axis=1)
        gained = arc[row[:, -1], col[:, -1]]
        j_goal = int(np.searchsorted(cum, min(inp.horizon, float(cum[-1]))))
        aim = ahead[min(j_goal, len(ahead) - 1)]
        follow = np.hypot(traj[:, -1, 0] - aim[0], traj[:, -1, 1] - aim[1])
        return self.follow * follow + self.align * align - self.progress * gained


def path_field(ahead: NDArray[np.float64], cum: NDArray[np.float64],
               costmap: Costmap) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Per local-costmap cell: metres to the nearest point of ``ahead`` and that point's arc length."""
    from scipy.ndimage import distance_transform_edt

    rows, cols = costmap.shape
    col, row = costmap.world_to_cell(ahead[:, 0], ahead[:, 1])
    inside = (col >= 0) & (col < cols) & (row >= 0) & (row < rows)
    arc_at = np.zeros((rows, cols))
    seed = np.ones((rows, cols), dtype=bool)
    if not inside.any():   # path ahead entirely off the local window: only its first point matters
        col, row = np.clip(col[:1], 0, cols - 1), np.clip(row[:1], 0, rows - 1)
        inside = np.ones(1, dtype=bool)
    seed[row[inside], col[inside]] = False
    arc_at[row[inside][::-1], col[inside][::-1]] = cum[inside][::-1]   # first visit wins on repeats
    dist, (ir, ic) = distance_transform_edt(seed, return_indices=True)
    return dist * costmap.resolution, arc_at[ir, ic]


class HeadingCritic:
    """Mean heading error to the target yaw (path direction, passage-fitting yaw or goal yaw)."""

    name = "HeadingCritic"

    def __init__(self, weight: float) -> None:
        self.weight = weight

    def score(self, inp: CriticInput) -> NDArray[np.float64]:
        dyaw = np.abs(wrap_angle(inp.traj[..., 2] - inp.heading_target))
        return self.weight * inp.heading_gain * dyaw.mean(axis=1)


class TwirlingCritic:
    """Mean squared turn rate."""

    name = "TwirlingCritic"

    def __init__(self, weight: float) -> None:
        self.weight = weight

    def score(self, inp: CriticInput) -> NDArray[np.float64]:
        return self.weight * np.mean(inp.u[..., 2] ** 2, axis=1)


class SmoothnessCritic:
    """Mean squared change between consecutive controls."""

    name = "SmoothnessCritic"

    def __init__(self, weight: float) -> None:
        self.weight = weight

    def score(self, inp: CriticInput) -> NDArray[np.float64]:
        return self.weight * np.mean(np.diff(inp.u, axis=1) ** 2, axis=(1, 2))


def build_critics(m: MppiConfig, sample_points: NDArray[np.float64],
                  margin_points: NDArray[np.float64]) -> list[Critic]:
    """The critics ``m`` switches on (weight > 0), the collision critic first and always."""
    critics: list[Critic] = [CollisionCritic(m.collision_cost, m.clearance_weight, m.clearance_margin,
                                             m.collision_stride, sample_points, margin_points)]
    optional: list[tuple[float, Critic]] = [
        (m.cost_weight, CostCritic(m.cost_weight)),
        (m.goal_weight, GoalCritic(m.goal_weight, m.goal_distance)),
        (max(m.path_follow_weight, m.path_align_weight, m.progress_weight),
         PathCritic(m.path_follow_weight, m.path_align_weight, m.progress_weight, m.goal_distance)),
        (m.heading_weight, HeadingCritic(m.heading_weight)),
        (m.twirling_weight, TwirlingCritic(m.twirling_weight)),
        (m.smoothness_weight, SmoothnessCritic(m.smoothness_weight)),
    ]
    return critics + [c for w, c in optional if w > 0]
