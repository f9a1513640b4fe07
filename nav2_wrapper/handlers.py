"""Contract handlers: navigate, navigate/status, navigate/cancel and the three speed contracts.

Bound to gRPC and MCP from process start. They read the current session through ``loop()`` (None
until CMD_INIT succeeds) and answer a clean "not initialized: <why>" instead of failing. The MCP
status tool returns the record structured (distance remaining, recoveries, goal, ...) as well.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import grpc

from nav2_wrapper.core import GoalRecord
from nav2_wrapper.core.navigator import FAILED, RUNNING, TERMINAL
from robonix_api import telemetry
from robonix_api.grpc_contracts import StatusError
from robonix_api.proto_gen import navigation_pb2 as nav_pb
from robonix_api.validation import ID_MAX, require_len

from .goals import parse_goal
from .loop import NavLoop
from .speed import SpeedResult

NS = "robonix/service/navigation/"
NAVIGATE, STATUS, CANCEL = NS + "navigate", NS + "navigate/status", NS + "navigate/cancel"
ADJUST, SET_LIMIT, GET_LIMIT = NS + "adjust_speed", NS + "set_speed_limit", NS + "get_speed_limit"
INACTIVE = "inactive: navigation is not active (send CMD_ACTIVATE)"
#: What status says about the run a crashed navigation process was driving, until its successor takes it
#: up again (never a terminal state that later changes: issue 37 item 8).
RESTARTING = ("restarting: navigation is starting again after a crash and will take this run up again "
              "(robot stopped meanwhile)")
#: Goals farther than this from the map origin are refused before planning (no map is that large).
MAX_ABS_COORD_M = 10_000.0


def _check_goal(req: nav_pb.Navigate_Request) -> None:
    """INVALID_ARGUMENT for a goal no map can hold or an overlong frame id (finite checks stay in parse_goal)."""
    if req.HasField("goal"):
        pos = req.goal.pose.position
        for name in ("x", "y", "z"):
            v = getattr(pos, name)
            if math.isfinite(v) and abs(v) > MAX_ABS_COORD_M:
                raise StatusError(grpc.StatusCode.INVALID_ARGUMENT, f"goal.pose.position.{name}: must be within "
                                  f"[-{MAX_ABS_COORD_M:g}, {MAX_ABS_COORD_M:g}] m, got {v:g}")
        require_len(req.goal.header, "frame_id", ID_MAX)


def _r(v: float, nd: int = 3) -> float | None:
    return round(v, nd) if math.isfinite(v) else None


class NavHandlers:
    """The contracts' handlers; ``loop()`` is the current session's NavLoop, ``not_ready()`` why there is none."""

    def __init__(self, loop: Callable[[], NavLoop | None], not_ready: Callable[[], str],
                 restarting: Callable[[], str] = lambda: "") -> None:
        """``restarting()``: the run id a crashed predecessor was driving while this process has not taken
        it up yet ("" otherwise)."""
        self._loop, self._not_ready, self._restarting = loop, not_ready, restarting

    def _restarting_run(self, run_id: str) -> str:
        """The run being taken up again after a crash when ``run_id`` (or "" = the latest) asks for it."""
        rid = self._restarting()
        return rid if rid and run_id in ("", rid) else ""

    def _uninit(self) -> str:
        return f"not initialized: {self._not_ready()}"

    # ---- navigate / status / cancel ----------------------------------------------------------------
    def navigate(self, req: nav_pb.Navigate_Request, ctx: Any = None) -> nav_pb.Navigate_Response:
        """Send the robot to goal (geometry_msgs/PoseStamped; frame "map" or empty = map, a unit quaternion
        for the final heading, e.g. w=1 for yaw 0). A new goal preempts the running one. Returns accepted,
        run_id (poll it with the status tool) and a one-line detail, or the reason for rejection."""
        _check_goal(req)
        loop = self._loop()
        if loop is None:
            return nav_pb.Navigate_Response(accepted=False, detail=self._uninit())
        goal = parse_goal(req.goal) if req.HasField("goal") else "goal: missing (a geometry_msgs/PoseStamped)"
        rec, preempted = loop.navigate(goal, telemetry.context_from_grpc(ctx))
        if rec is None:
            return nav_pb.Navigate_Response(accepted=False, detail=INACTIVE)
        if not rec.accepted:
            return nav_pb.Navigate_Response(accepted=False, run_id=rec.run_id, detail=rec.detail)
        x, y, yaw = rec.goal
        detail = f"accepted: goal ({x:.2f}, {y:.2f}, yaw {yaw:.2f}) in {loop.cfg.frames.map}"
        return nav_pb.Navigate_Response(accepted=True, run_id=rec.run_id,
                                        detail=detail + (f"; preempted {preempted}" if preempted else ""))

    def _lookup(self, run_id: str) -> tuple[NavLoop | None, GoalRecord | None, str]:
        if len(run_id) > ID_MAX:
            return self._loop(), None, f"run_id: at most {ID_MAX} characters, got {len(run_id)}"
        loop = self._loop()
        if loop is None:
            return None, None, self._uninit()
        rec = loop.status(run_id)
        if rec is None:
            return loop, None, f"unknown run_id {run_id!r}" if run_id else "no navigation run yet"
        return loop, rec, ""

    def status(self, req: nav_pb.GetNavigationStatus_Request) -> nav_pb.GetNavigationStatus_Response:
        _, rec, why = self._lookup(req.run_id)
        if rec is None and self._restarting_run(req.run_id):
            return nav_pb.GetNavigationStatus_Response(known=True, state=RUNNING, detail=RESTARTING)
        if rec is None:
            return nav_pb.GetNavigationStatus_Response(known=False, state=FAILED, detail=why)
        return nav_pb.GetNavigationStatus_Response(known=True, state=rec.state, detail=rec.detail)

    def status_mcp(self, req: nav_pb.GetNavigationStatus_Request) -> dict[str, Any]:
        """Status of a navigation run (empty run_id = the latest): state PENDING, RUNNING, SUCCEEDED, FAILED
        or CANCELED, a one-line detail (distance remaining, ETA, recoveries, or the failure reason), and the
        same structured: run_id, accepted, goal {x, y, yaw, frame}, distance_remaining_m, recoveries,
        started_s / finished_s (provider clock), speed_limit_percentage. Unknown runs: known=false."""
        loop, rec, why = self._lookup(req.run_id)
        rid = self._restarting_run(req.run_id) if rec is None else ""
        if rid:
            return {"known": True, "state": RUNNING, "detail": RESTARTING, "run_id": rid, "terminal": False}
        if rec is None or loop is None:
            return {"known": False, "state": FAILED, "detail": why, "run_id": req.run_id[:ID_MAX]}
        x, y, yaw = rec.goal
        left = loop.remaining(rec)
        return {"known": True, "state": rec.state, "detail": rec.detail, "run_id": rec.run_id,
                "accepted": rec.accepted, "terminal": rec.state in TERMINAL,
                "goal": {"x": _r(x), "y": _r(y), "yaw": _r(yaw), "frame": loop.cfg.frames.map},
                "distance_remaining_m": None if left is None else round(left, 3),
                "recoveries": rec.recoveries, "started_s": _r(rec.started),
                "finished_s": None if rec.finished is None else _r(rec.finished),
                "speed_limit_percentage": loop.speed.effective()[0]}

    def cancel(self, req: nav_pb.CancelNavigation_Request) -> nav_pb.CancelNavigation_Response:
        """Cancel a navigation run (empty run_id = the latest); a PENDING or RUNNING run becomes CANCELED
        and the robot is stopped at once. A run that already ended is reported, not changed."""
        loop, rec, why = self._lookup(req.run_id)
        if loop is None or rec is None:
            return nav_pb.CancelNavigation_Response(accepted=False, detail=why)
        rec, was_live = loop.cancel(rec.run_id)
        if rec is None:
            return nav_pb.CancelNavigation_Response(accepted=False, detail=f"unknown run_id {req.run_id!r}")
        if not was_live:
            return nav_pb.CancelNavigation_Response(accepted=False,
                                                    detail=f"run {rec.run_id} already {rec.state}: {rec.detail}")
        return nav_pb.CancelNavigation_Response(accepted=True, detail=f"run {rec.run_id} canceled; robot stopped")

    # ---- speed -------------------------------------------------------------------------------------
    @staticmethod
    def _speed_reply(cls: type, res: SpeedResult) -> Any:
        return cls(accepted=res.accepted, changed=res.changed, effective_percentage=res.percentage,
                   effective_linear_speed_mps=res.mps, scope=res.scope, run_id=res.run_id, detail=res.detail)

    def adjust_speed(self, req: nav_pb.AdjustNavigationSpeed_Request) -> nav_pb.AdjustNavigationSpeed_Response:
        """Step the speed limit: direction faster | slower | normal (by dynamic_speed.step_percentage).
        persist=true changes the session limit; otherwise it applies to the running goal (run_id or the
        active one) and reverts when that run ends."""
        require_len(req, "run_id", ID_MAX)
        require_len(req, "direction", ID_MAX)
        loop = self._loop()
        if loop is None:
            return nav_pb.AdjustNavigationSpeed_Response(accepted=False, detail=self._uninit())
        with loop.lock:
            res = loop.speed.adjust(req.direction, req.run_id, req.persist, loop.active_run())
            loop.apply_speed()
        return self._speed_reply(nav_pb.AdjustNavigationSpeed_Response, res)

    def set_speed_limit(self, req: nav_pb.SetNavigationSpeedLimit_Request) -> nav_pb.SetNavigationSpeedLimit_Response:
        """Set the speed limit as a percentage of max_linear_speed_mps (within [min_percentage, 100]);
        persist=true for the whole session, else for the running goal only."""
        require_len(req, "run_id", ID_MAX)
        loop = self._loop()
        if loop is None:
            return nav_pb.SetNavigationSpeedLimit_Response(accepted=False, detail=self._uninit())
        with loop.lock:
            res = loop.speed.set(req.percentage, req.run_id, req.persist, loop.active_run())
            loop.apply_speed()
        return self._speed_reply(nav_pb.SetNavigationSpeedLimit_Response, res)

    def get_speed_limit(self, req: nav_pb.GetNavigationSpeedLimit_Request) -> nav_pb.GetNavigationSpeedLimit_Response:
        """The speed limit configuration (dynamic_speed) and the limit in force, with its scope."""
        loop = self._loop()
        if loop is None:
            return nav_pb.GetNavigationSpeedLimit_Response(available=False, detail=self._uninit())
        with loop.lock:
            sp = loop.speed
            pct, scope, rid = sp.effective()
            return nav_pb.GetNavigationSpeedLimit_Response(
                available=True, max_linear_speed_mps=sp.max_mps, default_percentage=sp.cfg.default_percentage,
                min_percentage=sp.cfg.min_percentage, step_percentage=sp.cfg.step_percentage,
                effective_percentage=pct, effective_linear_speed_mps=sp.mps(pct), scope=scope, run_id=rid,
                detail=f"{pct:g}% of {sp.max_mps:.3f} m/s ({scope})")

    def table(self) -> dict[str, Any]:
        """contract id -> handler (or (gRPC, MCP) pair), for ``robonix_api.hosting.serve_contracts``."""
        return {NAVIGATE: self.navigate, STATUS: (self.status, self.status_mcp), CANCEL: self.cancel,
                ADJUST: self.adjust_speed, SET_LIMIT: self.set_speed_limit, GET_LIMIT: self.get_speed_limit}
