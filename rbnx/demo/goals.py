"""`rbnx demo` pure helpers: goal choice, nav-detail parsing, geometry. No I/O, so they are unit-testable."""

from __future__ import annotations

import math
import random
import re
from collections.abc import Sequence
from dataclasses import dataclass

# nav2_wrapper's RUNNING detail, e.g. "2.88 m remaining, ETA 6 s, 0 recoveries[, blocked]".
_DETAIL_RE = re.compile(r"(?P<left>[0-9.]+) m remaining, ETA (?P<eta>[0-9.]+) s(?:, (?P<rec>\d+) recoveries)?")
TERMINAL = ("SUCCEEDED", "FAILED", "CANCELED")
#: How the navigation provider's PENDING detail starts while its planner warms up (nav2_wrapper.warmup_note).
WARMING = "warming up the planner"


def warming_up(state: str, detail: str) -> bool:
    """A goal waiting for the planner's first-run warm-up: a client's timeout starts only after it."""
    return state == "PENDING" and detail.startswith(WARMING)


@dataclass(frozen=True)
class Goal:
    """A navigation target in the map frame (= the sim's world frame at start: SLAM's map starts at odom,
    and the HAL's odom frame is the world frame unless odom_frame_at_start is set)."""

    name: str
    x: float
    y: float
    yaw: float = 0.0


@dataclass(frozen=True)
class Progress:
    remaining_m: float | None
    eta_s: float | None
    recoveries: int | None


def parse_detail(detail: str) -> Progress:
    """Distance left / ETA / recoveries from the status detail; None fields when the line has none."""
    m = _DETAIL_RE.search(detail or "")
    if not m:
        return Progress(None, None, None)
    rec = m.group("rec")
    return Progress(float(m.group("left")), float(m.group("eta")), int(rec) if rec is not None else None)


def choose_goals(waypoints: dict[str, Sequence[float]], start_xy: tuple[float, float], n: int,
                 seed: int | None = None, min_dist: float = 1.0) -> list[Goal]:
    """N goals from the scene's waypoints in file order (shuffled with ``seed``), cycling when N exceeds
    them; a waypoint closer than ``min_dist`` to where the robot will be (start, then the previous goal)
    is skipped because reaching it proves nothing. Empty list when no waypoint qualifies."""
    pool = [Goal(str(k), float(v[0]), float(v[1])) for k, v in waypoints.items() if len(v) >= 2]
    if seed is not None:
        random.Random(seed).shuffle(pool)
    out: list[Goal] = []
    here = start_xy
    i = misses = 0
    while pool and len(out) < n and misses < len(pool):
        g = pool[i % len(pool)]
        i += 1
        if math.hypot(g.x - here[0], g.y - here[1]) < min_dist:
            misses += 1
            continue
        misses = 0
        out.append(g)
        here = (g.x, g.y)
    return out


def path_length(points: Sequence[Sequence[float]]) -> float:
    """Sum of segment lengths of an (x, y, ...) polyline."""
    return sum(math.hypot(b[0] - a[0], b[1] - a[1]) for a, b in zip(points, points[1:], strict=False))


def fmt_s(seconds: float | None) -> str:
    if seconds is None or not math.isfinite(seconds):
        return "-"
    if seconds < 60:
        return f"{seconds:.1f}s"
    return f"{int(seconds // 60)}m{seconds % 60:04.1f}s"
