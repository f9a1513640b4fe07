"""A predictive sampling controller (MPPI) for the holonomic base, in the spirit of Nav2's MPPIController
with its Omni motion model.

Each step perturbs the previous optimal control sequence (vx, vy, wz over ``time_steps`` × ``model_dt``)
with Gaussian noise, rolls the perturbed sequences out through the omni kinematics, scores every
trajectory with a handful of critics (collision, costmap cost, path following and progress, goal, heading,
smoothness), and blends them with a softmax of temperature ``temperature``. The first control of the blend
is the command; the rest warm-starts the next step.

Why a subclass of the pursuit controller: the heading targets (path direction, the passage-fitting yaw,
the goal yaw), the exact footprint trajectory check and the escape move are already there and are what
the navigator's recoveries call. MPPI replaces only how a command is chosen; the command it picks is
checked with the same exact footprint test, and if it fails, the pursuit's own candidates and escape run
instead, so switching controllers never loosens the safety check.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from robonix_common.geometry import Pose2D
from robonix_common.params import param

from .controller import ControllerConfig, ControlOutput, HolonomicController
from .costmap import Costmap
from .critics import CriticInput, build_critics
from .interfaces import Critic


@dataclass
class MppiConfig:
    """MPPI sampling parameters (Nav2 names and defaults where Nav2 has them) and the critics' weights.

    A critic weight of 0 switches that critic off; the collision critic cannot be switched off."""

    batch_size: int = param(1000, "sampled control sequences per step", ge=16, le=20000)
    time_steps: int = param(56, "steps per sampled sequence (horizon = time_steps * model_dt)", ge=2, le=500)
    model_dt: float = param(0.05, "time between two steps of a sequence", unit="s", gt=0, le=1.0)
    vx_std: float = param(0.2, "sampling noise on vx", unit="m/s", ge=0)
    vy_std: float = param(0.2, "sampling noise on vy", unit="m/s", ge=0)
    wz_std: float = param(0.4, "sampling noise on wz", unit="rad/s", ge=0)
    temperature: float = param(0.3, "softmax temperature: lower follows the best sample more closely", gt=0)
    collision_stride: int = param(2, "steps between footprint checks of the samples", ge=1, le=50)
    outline_spacing: float = param(0.1, "spacing of the footprint outline points checked for the samples",
                                   unit="m", gt=0, le=1.0)
    seed: int = param(0, "noise seed: the same seed and inputs give the same commands", ge=0)
    collision_cost: float = param(10000.0, "cost of a sample whose footprint adds a lethal contact", gt=0)
    cost_weight: float = param(3.0, "weight of the mean normalised costmap cost along a sample", ge=0)
    clearance_margin: float = param(0.05, "body clearance a sample should keep: its footprint grown by this is "
                                    "checked for lethal cells", unit="m", ge=0, le=0.3)
    clearance_weight: float = param(0.0, "weight of the share of a sample's checked poses whose footprint "
                                    "grown by clearance_margin touches a lethal cell (0: off, see _collisions)",
                                    ge=0)
    path_follow_weight: float = param(5.0, "weight of the end point's distance to where the horizon should reach",
                                      ge=0)
    progress_weight: float = param(4.0, "reward per metre of path gained by a sample", ge=0)
    path_align_weight: float = param(10.0, "weight of a sample's mean distance to the path", ge=0)
    goal_weight: float = param(5.0, "near the goal: weight of a sample's mean distance to it", ge=0)
    goal_distance: float = param(1.0, "distance to the goal where the goal critic replaces path following",
                                 unit="m", gt=0)
    heading_weight: float = param(2.0, "weight of the mean heading error (path direction, passage yaw, goal yaw)",
                                  ge=0)
    passage_heading_gain: float = param(
        3.0, "the heading weight is multiplied by this while the target is the passage-fitting yaw (1: no change)",
        ge=1.0, le=20.0)
    twirling_weight: float = param(0.1, "weight of the mean squared turn rate", ge=0)
    smoothness_weight: float = param(0.5, "weight of the mean squared change between consecutive controls", ge=0)


class MppiController(HolonomicController):
    """Drop-in replacement for :class:`HolonomicController` that chooses commands by MPPI."""

    def __init__(self, cfg: ControllerConfig | None = None, mppi: MppiConfig | None = None) -> None:
        self.mppi = mppi or MppiConfig()
        m = self.mppi
        self._u = np.zeros((m.time_steps, 3))      # before the base class sets the first (empty) path
        super().__init__(cfg)
        self._rng = np.random.default_rng(m.seed)
        self._sample_points = self.cfg.footprint.outline_points(m.outline_spacing)
        self._margin_points = self.cfg.footprint.padded(m.clearance_margin).outline_points(m.outline_spacing)
        self.critics: list[Critic] = build_critics(m, self._sample_points, self._margin_points)
        self.last_samples: NDArray[np.float64] | None = None   # (K, T, 3) poses of the last step, for display

    def set_path(self, path: NDArray[np.float64], headings: NDArray[np.float64] | None = None) -> None:
        super().set_path(path, headings)
        self._u[:] = 0.0

    def _compute(self, pose: Pose2D, vel: Pose2D, goal: Pose2D, costmap: Costmap, dt: float,
                 xy_reached: bool = False) -> ControlOutput:
        """One control step from the pose where the command will act (see ``HolonomicController.compute``)."""
        if len(self.path) == 0 or xy_reached:
            # the final turn in place is the pursuit's job: nothing to predict there
            return super()._compute(pose, vel, goal, costmap, dt, xy_reached)
        i = self._closest(pose[0], pose[1])
        remaining = self.remaining(pose)
        target, gain = self._heading_target_and_gain(i, pose, goal, costmap)
        cmd = self._optimise(pose, vel, goal, costmap, i, target, gain)
        # vx and vy are sampled within their own limits, so together they could reach √2 × either: hold the
        # planar speed to the cruise speed the profile (and the pursuit) drive at
        vmax = self.cfg.desired_linear_vel * self.speed_limit
        v = math.hypot(cmd[0], cmd[1])
        if v > vmax:
            cmd = (cmd[0] * vmax / v, cmd[1] * vmax / v, *cmd[2:])
        cand = np.array([cmd])
        if not self.trajectory_hits(cand, pose, costmap)[0]:
            return ControlOutput(*cmd, False, remaining, "mppi")
        fallback = super()._compute(pose, vel, goal, costmap, dt, xy_reached)
        self._u[:] = 0.0
        fallback.detail = "mppi fallback"
        return fallback

    # ---- the optimiser -----------------------------------------------------------------------------------
    def _heading_target(self, i: int, pose: Pose2D, goal: Pose2D, costmap: Costmap) -> float:
        """The yaw the body should hold (see :meth:`_heading_target_and_gain`)."""
        return self._heading_target_and_gain(i, pose, goal, costmap)[0]

    def _heading_target_and_gain(self, i: int, pose: Pose2D, goal: Pose2D, costmap: Costmap) -> tuple[float, float]:
        """The yaw the body should hold and the factor on the heading critic's weight: the planner's heading
        when the path has one (the footprint-aware fallback planned it), else the passage-fitting yaw in a narrow
        spot, else the path direction (either end leading); near the goal the goal's yaw.

        Why a larger weight for the passage yaw (``passage_heading_gain``): at the base weight the samples that
        keep progressing along the path win over those that turn, and the body reached a 1.1 m doorway still
        turning, its long axis 30–50° off square (bench/doorway_crossings.py, random:7: median skew 33°, closest
        4.5 cm). Weighted up only there (gain 3: median skew 13°, closest 9.2 cm; over random:1–8, 264 crossings,
        closest 1.0 → 4.1 cm, median 10.4 → 13.0 cm), the turn is mostly finished before the jambs; elsewhere
        following the path keeps its weight."""
        th = pose[2]
        if math.hypot(goal[0] - pose[0], goal[1] - pose[1]) < self.cfg.rotate_to_goal_dist:
            return float(goal[2]), 1.0
        planned = self.planned_yaw(i)
        if planned is not None:
            return self._nearest_end(planned, th), 1.0
        passage = self._passage_yaw(i, th, costmap)
        if passage is not None:
            return self._nearest_end(passage, th), self.mppi.passage_heading_gain
        return self._nearest_end(self._path_yaw(i, self._half_length, th, ahead=True), th), 1.0

    def _limits(self) -> NDArray[np.float64]:
        c = self.cfg
        return np.array([c.max_vel_x, c.max_vel_y, c.max_vel_theta]) * self.speed_limit

    def _sample(self, pose: Pose2D, vel: Pose2D) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Perturbed control sequences (K, T, 3), limited in velocity and acceleration, and their rollouts
        through the omni kinematics (body-frame velocities rotated by the heading at each step's start)."""
        from ._mppi_kernels import limit_and_rollout

        m, c = self.mppi, self.cfg
        std = np.array([m.vx_std, m.vy_std, m.wz_std])
        u = self._u[None] + self._rng.standard_normal((m.batch_size, m.time_steps, 3)) * std
        u[0] = self._u             # the previous optimum itself is always a candidate
        u[1] = 0.0                 # and so is stopping
        acc = np.array([c.acc_lim_x, c.acc_lim_y, c.acc_lim_theta]) * m.model_dt
        traj = np.empty_like(u)
        limit_and_rollout(u, np.asarray(vel, dtype=float), np.asarray(pose, dtype=float), self._limits(), acc,
                          float(m.model_dt), traj)
        return u, traj

    def _optimise(self, pose: Pose2D, vel: Pose2D, goal: Pose2D, costmap: Costmap, i: int,
                  target: float, heading_gain: float = 1.0) -> tuple[float, float, float]:
        m = self.mppi
        u, traj = self._sample(pose, vel)
        cost = self._score(pose, goal, costmap, traj, u, i, target, heading_gain)
        cost -= cost.min()
        w = np.exp(-cost / max(m.temperature, 1e-6))
        w /= w.sum()
        self._u = np.tensordot(w, u, axes=1)
        self.last_samples = traj
        cmd = self._u[0].copy()
        self._u = np.vstack([self._u[1:], self._u[-1:]])   # warm start: shift by one step
        return float(cmd[0]), float(cmd[1]), float(cmd[2])

    def _score(self, pose: Pose2D, goal: Pose2D, costmap: Costmap, traj: NDArray[np.float64],
               u: NDArray[np.float64], i: int, target: float, heading_gain: float = 1.0) -> NDArray[np.float64]:
        """Sum of the critics' costs (``critics``, built from the config) for the K sampled trajectories."""
        m, c = self.mppi, self.cfg
        inp = CriticInput(pose, goal, costmap, traj, u, self.path, self.path_cum, i,
                          m.time_steps * m.model_dt * c.desired_linear_vel * self.speed_limit, target, heading_gain)
        cost = np.zeros(len(traj))
        for critic in self.critics:
            cost += critic.score(inp)
        return cost
