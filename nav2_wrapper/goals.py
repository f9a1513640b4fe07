"""Checks on a Navigate goal that need no map: finite numbers, a unit quaternion, a frame name.

Map-dependent checks (off the map, inside an obstacle) belong to the core's ``validate_goal``; the
frame itself is resolved against TF by the loop. Each reason names the offending field so a caller (or
an agent) can fix the request.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from robonix_common.geometry import quat_norm, quat_to_yaw

QUAT_TOLERANCE = 1e-3


@dataclass(frozen=True)
class PlanarGoal:
    x: float
    y: float
    yaw: float
    frame: str  # "" means the global (map) frame


def parse_goal(goal: Any) -> PlanarGoal | str:
    """``PlanarGoal`` from a PoseStamped proto, or the reason it is rejected."""
    p, q = goal.pose.position, goal.pose.orientation
    for name, v in (("x", p.x), ("y", p.y), ("z", p.z)):
        if not math.isfinite(v):
            return f"goal.pose.position.{name}: non-finite value ({v})"
    for name, v in (("x", q.x), ("y", q.y), ("z", q.z), ("w", q.w)):
        if not math.isfinite(v):
            return f"goal.pose.orientation.{name}: non-finite value ({v})"
    n = quat_norm(q.x, q.y, q.z, q.w)
    if abs(n - 1.0) > QUAT_TOLERANCE:
        hint = " (for yaw 0 send w=1)" if n == 0.0 else ""
        return f"goal.pose.orientation: quaternion not normalised (norm {n:.6g}){hint}"
    frame = goal.header.frame_id.strip().lstrip("/")
    if " " in frame:
        return f"goal.header.frame_id: invalid frame name {goal.header.frame_id!r}"
    return PlanarGoal(float(p.x), float(p.y), quat_to_yaw(q.x, q.y, q.z, q.w), frame)
