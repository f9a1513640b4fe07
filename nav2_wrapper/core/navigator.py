"""The navigator state machine: one goal at a time, PENDING → RUNNING → SUCCEEDED / FAILED / CANCELED.

It owns no thread and reads no clock: the provider calls ``tick(now, pose, vel, grid, scan)`` at the
controller rate with sim (or wall) time, which is what makes the core deterministic and testable.
The behaviour follows Nav2's navigate_to_pose tree: replan at a fixed rate (and at once when the path
is blocked), follow with the controller, check goal and progress, and on failure run the recoveries
round-robin until the retry budget is spent.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

import numpy as np

from robonix_common.geometry import Pose2D
from robonix_common.grid import GridMap
from robonix_common.params import param
from robonix_common.scan import Scan

from . import escape as esc
from .checkers import BLOCKED, SLOW, GoalChecker, GoalCheckerConfig, ProgressChecker, ProgressCheckerConfig
from .controller import ControllerConfig, HolonomicController
from .costmap import Costmap, CostmapConfig
from .costs import INSCRIBED, LETHAL
from .footprint import Footprint
from .footprint_planning import FootprintAwarePlanner
from .mppi import MppiConfig, MppiController
from .planner import GlobalPlanner, PlannerConfig, PlanResult
from .recoveries import RecoveryConfig, RecoverySequence

PENDING, RUNNING, SUCCEEDED, FAILED, CANCELED, IDLE = "PENDING", "RUNNING", "SUCCEEDED", "FAILED", "CANCELED", "IDLE"
TERMINAL = (SUCCEEDED, FAILED, CANCELED)


@dataclass
class NavigatorConfig:
    """The navigate-to-pose behaviour (``bt_navigator``, plus the controller rate from ``controller_server``)."""

    replan_frequency: float = param(1.0, "replan rate (BT RateController); also at once on a blocked path",
                                    unit="Hz", gt=0)
    controller_frequency: float = param(20.0, "control loop rate", unit="Hz", gt=0)
    path_blocked_lookahead: float = param(2.5, "path checked for new lethal/inscribed cells each tick", unit="m",
                                          gt=0)
    min_replan_interval: float = param(0.25, "minimum time between event-triggered replans", unit="s", ge=0)
    blocked_timeout: float = param(2.0, "time the controller may find no safe command before a recovery",
                                   unit="s", gt=0)
    pending_timeout: float = param(30.0, "time a goal may wait for the first map and pose", unit="s", gt=0)
    input_grace_s: float = param(5.0, "time a goal stays paused, robot stopped, while a required input is lost",
                                 unit="s", ge=0, le=3600)
    unknown_goal_margin: float = param(
        10.0, "how far beyond the current map a goal may lie when planning through unknown space", unit="m", ge=0)
    global_frame: str = param("map", "frame goals and plans are in (the provider's frames config wins)")
    robot_base_frame: str = param("base_link", "robot base frame (the provider's frames config wins)")


def _local_default(footprint: Footprint) -> CostmapConfig:
    return CostmapConfig(name="local_costmap", rolling_window=True, width=3.0, height=3.0, static_layer=False,
                         footprint=footprint)


@dataclass
class NavConfig:
    """Everything the navigator needs; ``nav2_wrapper.params`` builds it from a Nav2 params profile."""

    global_costmap: CostmapConfig
    local_costmap: CostmapConfig
    controller: ControllerConfig
    planner: PlannerConfig = field(default_factory=PlannerConfig)
    goal_checker: GoalCheckerConfig = field(default_factory=GoalCheckerConfig)
    progress_checker: ProgressCheckerConfig = field(default_factory=ProgressCheckerConfig)
    recovery: RecoveryConfig = field(default_factory=RecoveryConfig)
    navigator: NavigatorConfig = field(default_factory=NavigatorConfig)
    mppi: MppiConfig | None = None      # set: the MPPI controller; None: the holonomic pursuit controller

    @classmethod
    def defaults(cls, footprint: Footprint) -> NavConfig:
        """Every parameter at its declared default, for the given robot footprint."""
        return cls(CostmapConfig(footprint=footprint), _local_default(footprint),
                   ControllerConfig(footprint=footprint))


@dataclass
class Command:
    vx: float
    vy: float
    wz: float
    state: str
    detail: str
    run_id: str = ""


@dataclass
class GoalRecord:
    run_id: str
    goal: Pose2D
    state: str = PENDING
    detail: str = "waiting to start"
    accepted: bool = True
    recoveries: int = 0
    started: float = 0.0
    finished: float | None = None


def validate_goal(x: float, y: float, yaw: float, costmap: Costmap) -> str | None:
    """None if the goal may be planned to; else the specific reason it may not."""
    if not all(math.isfinite(v) for v in (x, y, yaw)):
        return f"goal has non-finite coordinates ({x}, {y}, {yaw})"
    c, r = costmap.world_to_cell(x, y)
    if not bool(costmap.in_bounds(c, r)):
        rows, cols = costmap.shape
        x1, y1 = costmap.origin_x + cols * costmap.resolution, costmap.origin_y + rows * costmap.resolution
        return (f"goal ({x:.2f}, {y:.2f}) is off the map (x {costmap.origin_x:.2f}..{x1:.2f}, "
                f"y {costmap.origin_y:.2f}..{y1:.2f})")
    if int(costmap.costs[int(r), int(c)]) == LETHAL:
        return f"goal ({x:.2f}, {y:.2f}) is inside an obstacle"
    return None


class Navigator:
    def __init__(self, cfg: NavConfig) -> None:
        self.cfg = cfg
        self.global_costmap = Costmap(self.cfg.global_costmap)
        self.local_costmap = Costmap(self.cfg.local_costmap)
        self.planner = GlobalPlanner(self.cfg.planner)
        self.footprint_planner = FootprintAwarePlanner(self.planner, self.cfg.global_costmap.footprint)
        self.controller = (HolonomicController(self.cfg.controller) if self.cfg.mppi is None
                           else MppiController(self.cfg.controller, self.cfg.mppi))
        self.goal_checker = GoalChecker(self.cfg.goal_checker)
        self.progress = ProgressChecker(self.cfg.progress_checker)
        self._scan_pts: np.ndarray | None = None
        self.recovery = RecoverySequence(self.cfg.recovery, self.clear_costmaps, lambda: self._scan_pts)
        self.records: dict[str, GoalRecord] = {}
        self.active: GoalRecord | None = None
        self.latest: GoalRecord | None = None
        self.path = np.zeros((0, 2))
        self.has_map = False
        self._map: GridMap | None = None
        self._ids = itertools.count(1)
        self._last_tick: float | None = None
        self._reset_run()

    # ---- goal API ---------------------------------------------------------------------------------
    def navigate(self, x: float, y: float, yaw: float, now: float, run_id: str | None = None) -> GoalRecord:
        """Accept a goal (preempting the running one) or reject it with a reason (accepted=False, FAILED)."""
        rid = run_id or f"nav-{next(self._ids)}"
        rec = GoalRecord(rid, (float(x), float(y), float(yaw)), started=now)
        self.records[rid] = rec
        self.latest = rec
        if self._map is not None and all(math.isfinite(v) for v in (x, y)):
            self.global_costmap.set_static_map(self._global_map(self._map, [*self._goals(), (x, y)]))
        finite = all(math.isfinite(v) for v in (x, y, yaw))
        reason = validate_goal(x, y, yaw, self.global_costmap) if self.has_map else (
            None if finite else f"goal has non-finite coordinates ({x}, {y}, {yaw})")
        if reason:
            rec.accepted = False
            self._finish(rec, FAILED, f"rejected: {reason}", now)
            return rec
        if self.active is not None and self.active.state not in TERMINAL:
            self._finish(self.active, CANCELED, f"preempted by {rid}", now)
        self.active = rec
        self._reset_run()
        return rec

    def cancel(self, now: float, run_id: str | None = None) -> GoalRecord | None:
        """Cancel the given (or the running) goal; the next tick commands zero velocity."""
        rec = self.records.get(run_id) if run_id else self.active
        if rec is None:
            return None
        if rec.state not in TERMINAL:
            self._finish(rec, CANCELED, "canceled", now)
        return rec

    def status(self, run_id: str | None = None) -> GoalRecord | None:
        return self.records.get(run_id) if run_id else self.latest

    # ---- pause (a required input is gone; the provider decides when, see core/grace.py) ------------
    @property
    def paused(self) -> bool:
        return self._paused

    def pause(self, detail: str) -> None:
        """Hold the running goal: it stays RUNNING (or PENDING) with ``detail``; ticks command zero."""
        rec = self.active
        if rec is None or rec.state in TERMINAL:
            return
        self._paused = True
        rec.detail = detail

    def resume(self) -> None:
        """Carry on after a pause: replan at once (the world moved on) and restart the progress window,
        so the seconds spent standing still do not count as "no progress"."""
        if not self._paused:
            return
        self._paused = False
        self.progress.reset()
        self._force_replan = True
        self._blocked_since = None

    def set_speed_limit(self, limit: float, percentage: bool = True) -> None:
        self.controller.set_speed_limit(limit, percentage)

    def clear_costmaps(self) -> None:
        self.global_costmap.clear()
        self.local_costmap.clear()

    # ---- the tick ---------------------------------------------------------------------------------
    def tick(self, now: float, pose: Pose2D, vel: tuple[float, float, float] = (0.0, 0.0, 0.0),
             grid: GridMap | None = None, scan: Scan | None = None,
             sensor_pose: Pose2D | None = None) -> Command:
        """Fold in new data, advance the active goal, and return the velocity command (body frame)."""
        dt = (now - self._last_tick) if self._last_tick is not None else 1.0 / self.cfg.navigator.controller_frequency
        self._last_tick = now
        pose = (float(pose[0]), float(pose[1]), float(pose[2]))
        self._update_costmaps(pose, grid, scan, sensor_pose)
        rec = self.active
        if rec is None or rec.state in TERMINAL:
            shown = rec or self.latest
            return Command(0.0, 0.0, 0.0, shown.state if shown else IDLE, shown.detail if shown else "idle",
                           shown.run_id if shown else "")
        if self._paused:
            return self._zero(rec)
        if rec.state == PENDING and not self._start(rec, now, pose):
            return self._zero(rec)
        return self._run(rec, now, pose, vel, dt)

    def _update_costmaps(self, pose: Pose2D, grid: GridMap | None, scan: Scan | None,
                         sensor_pose: Pose2D | None) -> None:
        if grid is not None:
            self._map = grid
            self.global_costmap.set_static_map(self._global_map(grid, self._goals()))
            self.local_costmap.set_static_map(grid)
            self.has_map = True
        self.local_costmap.update_origin(pose[0], pose[1])
        if scan is not None:
            sp = sensor_pose if sensor_pose is not None else pose
            self.global_costmap.update_scan(scan, sp)
            self.local_costmap.update_scan(scan, sp)
            self._scan_pts = esc.scan_points(scan, sp)

    def _start(self, rec: GoalRecord, now: float, pose: Pose2D) -> bool:
        if not self.has_map:
            if now - rec.started > self.cfg.navigator.pending_timeout:
                self._finish(rec, FAILED, "no map received within "
                             f"{self.cfg.navigator.pending_timeout:.0f} s", now)
            else:
                rec.detail = "waiting for the first map"
            return False
        reason = validate_goal(*rec.goal, self.global_costmap)
        if reason:
            self._finish(rec, FAILED, reason, now)
            return False
        res = self._plan(pose, now)
        if not res.ok:                      # Nav2: ComputePathToPose retried once after clearing the global costmap
            self.global_costmap.clear()
            res = self._plan(pose, now)
        if not res.ok:
            self._finish(rec, FAILED, res.reason, now)
            return False
        rec.state = RUNNING
        rec.detail = f"running: {res.length:.2f} m path"
        return True

    def _run(self, rec: GoalRecord, now: float, pose: Pose2D, vel: tuple[float, float, float], dt: float) -> Command:
        nc = self.cfg.navigator
        if self.recovery.active is not None:
            step = self.recovery.step(now, pose, self.local_costmap, self.controller)
            if not step.done:
                rec.detail = f"recovering: {self.recovery.active.name} ({rec.recoveries} recoveries)"
                return Command(step.vx, step.vy, step.wz, rec.state, rec.detail, rec.run_id)
            self._force_replan = True
            self.progress.reset()
            self._last_cmd_speed = None
        if self.goal_checker.is_goal_reached(pose, rec.goal, vel):
            err = math.hypot(pose[0] - rec.goal[0], pose[1] - rec.goal[1])
            self._finish(rec, SUCCEEDED, f"reached goal ({err:.2f} m from it, {rec.recoveries} recoveries)", now)
            return self._zero(rec)
        due = now - self._last_plan >= 1.0 / nc.replan_frequency
        urgent = (self._force_replan or self._path_blocked(pose)) and now - self._last_plan >= nc.min_replan_interval
        if self.footprint_planner.pending:
            self._carry_on()
        elif due or urgent:
            res = self._plan(pose, now, self.cfg.planner.se2.tick_expansions if len(self.path) else None)
            if not res.ok:
                return self._recover(rec, now, pose, res.reason)
        prog = self.progress.assess(now, pose, command=self._last_cmd_speed, remaining=self._last_remaining,
                                    pressed=self._pressed(pose, vel))
        if not prog.ok:
            self.progress.reset()
            return self._recover(rec, now, pose, prog.detail, prefer="escape" if prog.state == BLOCKED else None)
        out = self.controller.compute(pose, vel, rec.goal, self.local_costmap, dt,
                                      self.goal_checker.xy_reached(pose, rec.goal))
        if out.blocked:
            self._force_replan = True
            if self._blocked_since is None:
                self._blocked_since = now
            elif now - self._blocked_since > nc.blocked_timeout:
                self._blocked_since = None
                return self._recover(rec, now, pose, "blocked: controller found no collision-free command",
                                     prefer="escape")
        else:
            self._blocked_since = None
        self._last_cmd_speed, self._last_remaining = math.hypot(out.vx, out.vy), out.remaining
        speed = max(self.cfg.controller.desired_linear_vel * self.controller.speed_limit, 1e-3)
        rec.detail = (f"{out.remaining:.2f} m remaining, ETA {out.remaining / speed:.0f} s, "
                      f"{rec.recoveries} recoveries" + (", blocked" if out.blocked else "")
                      + (f", {prog.detail}" if prog.state == SLOW else ""))
        return Command(out.vx, out.vy, out.wz, rec.state, rec.detail, rec.run_id)

    # ---- helpers ----------------------------------------------------------------------------------
    def _goals(self) -> list[tuple[float, float]]:
        rec = self.active
        return [(rec.goal[0], rec.goal[1])] if rec is not None and rec.state not in TERMINAL else []

    def _global_map(self, grid: GridMap, goals: list[tuple[float, float]]) -> GridMap:
        """With allow_unknown, pad the map with unknown cells so goals up to ``unknown_goal_margin`` beyond it
        lie on the global costmap: a SLAM map covers only what was seen so far, and goals may be beyond."""
        if not goals or not self.cfg.planner.allow_unknown or abs(grid.origin_yaw) > 1e-9:
            return grid
        res = grid.resolution
        room = self.cfg.global_costmap.inflation_radius + self.cfg.planner.tolerance + res
        x0, y0 = grid.origin_x, grid.origin_y
        x1, y1 = x0 + grid.width * res, y0 + grid.height * res
        lo_x, lo_y, hi_x, hi_y = x0, y0, x1, y1
        for gx, gy in goals:
            if max(x0 - gx, gx - x1, y0 - gy, gy - y1) <= self.cfg.navigator.unknown_goal_margin:
                lo_x, lo_y = min(lo_x, gx - room), min(lo_y, gy - room)
                hi_x, hi_y = max(hi_x, gx + room), max(hi_y, gy + room)
        left, bottom = math.ceil((x0 - lo_x) / res - 1e-9), math.ceil((y0 - lo_y) / res - 1e-9)
        right, top = math.ceil((hi_x - x1) / res - 1e-9), math.ceil((hi_y - y1) / res - 1e-9)
        if left == right == bottom == top == 0:
            return grid
        data = np.pad(grid.data, ((bottom, top), (left, right)), constant_values=-1)
        return GridMap(data, res, x0 - left * res, y0 - bottom * res, 0.0, grid.frame_id)

    def _plan(self, pose: Pose2D, now: float, budget: int | None = None) -> PlanResult:
        """Plan from the pose (the 2D plan, refined for the footprint). With a ``budget``, an SE(2) search that
        needs more than that many expansions goes on at the next ticks (``_carry_on``) and the current path is
        kept meanwhile: the result is then that path."""
        goal = self.active.goal if self.active else pose
        res: PlanResult | None = self.planner.plan(self.global_costmap, (pose[0], pose[1]), (goal[0], goal[1]))
        if res is not None and res.ok:
            res = self.footprint_planner.refine(self.global_costmap, pose, (goal[0], goal[1]), res, budget)
        self._last_plan = now
        self._force_replan = False
        if res is None:
            return PlanResult(True, self.path, length=float(np.sum(np.hypot(*np.diff(self.path, axis=0).T))))
        if res.ok:
            self._adopt(res)
        return res

    def _carry_on(self) -> None:
        """One more slice of a pending SE(2) search; its path is taken when it ends (a failed search leaves
        the 2D path it was begun for)."""
        res = self.footprint_planner.advance(self.cfg.planner.se2.tick_expansions)
        if res is not None and res.ok:
            self._adopt(res)

    def _adopt(self, res: PlanResult) -> None:
        self.path = res.path
        self.controller.set_path(res.path, res.headings)

    def _path_blocked(self, pose: Pose2D) -> bool:
        """New lethal/inscribed cells on the next stretch of the path (outside the start-escape zone)."""
        p = self.controller.path
        if len(p) == 0:
            return False
        i = max(self.controller.progress_index, 0)
        j = self.controller.index_ahead(i, self.cfg.navigator.path_blocked_lookahead)
        seg = p[i:j + 1]
        far = np.hypot(seg[:, 0] - pose[0], seg[:, 1] - pose[1]) > self.cfg.planner.escape_radius
        seg = seg[far]
        if len(seg) == 0:
            return False
        c = self.global_costmap.cost_at(seg[:, 0], seg[:, 1], outside=0)
        cl = self.local_costmap.cost_at(seg[:, 0], seg[:, 1], outside=0)
        return bool(np.any(((c >= INSCRIBED) & (c <= LETHAL)) | ((cl >= INSCRIBED) & (cl <= LETHAL))))

    def _pressed(self, pose: Pose2D, vel: tuple[float, float, float]) -> bool:
        """Standing (nearly) still with the footprint at the escape margin toward the path: the progress
        checker's cue that the base is blocked, not slow. Skipped while moving (it costs a clearance query)."""
        p = self.controller.path
        if len(p) == 0 or math.hypot(vel[0], vel[1]) >= self.cfg.progress_checker.blocked_speed:
            return False
        i = int(np.argmin(np.hypot(p[:, 0] - pose[0], p[:, 1] - pose[1])))
        j = self.controller.index_ahead(i, 0.5)
        rc = self.cfg.recovery
        obs = esc.gather_obstacles(self.local_costmap, pose[0], pose[1], rc.escape_reach, self._scan_pts)
        return esc.blocked_toward(self.cfg.controller.footprint.polygon, pose, obs,
                                  (p[j, 0] - pose[0], p[j, 1] - pose[1]), rc.escape_margin)

    def _recover(self, rec: GoalRecord, now: float, pose: Pose2D, why: str, prefer: str | None = None) -> Command:
        beh = self.recovery.begin(now, pose, prefer)
        if beh is None:
            self._finish(rec, FAILED, f"{why}; gave up after {rec.recoveries} recoveries", now)
            return self._zero(rec)
        rec.recoveries += 1
        rec.detail = f"recovering: {beh.name} after: {why} ({rec.recoveries} recoveries)"
        self.controller.set_path(self.controller.path)
        return Command(0.0, 0.0, 0.0, rec.state, rec.detail, rec.run_id)

    def _reset_run(self) -> None:
        self.footprint_planner.forget()
        self.recovery.reset()
        self.goal_checker.reset()
        self.progress.reset()
        self.controller.set_path(np.zeros((0, 2)))
        self.path = np.zeros((0, 2))
        self._last_plan = -math.inf
        self._force_replan = False
        self._blocked_since: float | None = None
        self._last_cmd_speed: float | None = None
        self._last_remaining: float | None = None
        self._paused = False

    def _finish(self, rec: GoalRecord, state: str, detail: str, now: float) -> None:
        rec.state, rec.detail, rec.finished = state, detail, now
        if rec is self.active:
            self.controller.set_path(np.zeros((0, 2)))

    @staticmethod
    def _zero(rec: GoalRecord) -> Command:
        return Command(0.0, 0.0, 0.0, rec.state, rec.detail, rec.run_id)
