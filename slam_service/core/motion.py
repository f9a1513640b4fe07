"""How much to trust an odometry step: search windows, glitch suspicion and fallback edge uncertainty.

Motion is never thrown away. A long step (a data gap during a fast turn, a burst of travel between two
scans) is still what the wheels measured; it is only less certain. So the correlative search windows grow
with the step and with the gap instead of the scan being dropped, and a step faster than the robot can
move is suspected to be an odometry glitch: the matcher then also tries "the robot did not move".
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

from .types import SlamConfig


@dataclass(frozen=True)
class StepWindows:
    """Sequential search windows for one scan and whether they were widened."""

    xy: float  # m half-width
    theta: float  # rad half-width
    wide: bool


DEFAULT_PERIOD_S = 0.1  # s, scan period assumed before a stream's own is known
GAP_PERIODS = 5.0  # a data gap counts only when it is this many of the stream's own mean scan periods


class ScanClock:
    """The stream's mean scan period over its last scans, so stamp irregularity is judged against the
    stream itself. Real loggers stamp in bursts (the Intel log: a third of its scans < 20 ms after the
    previous one, then gaps of 0.5 s): the gap between two stamps is then not the time the robot had to
    move, and odometry steps over it are neither suspect nor a reason to widen the search."""

    def __init__(self, memory: int = 32) -> None:
        self._stamps: deque[float] = deque(maxlen=memory)

    def period(self) -> float | None:
        """Mean spacing of the remembered stamps (None before two scans or if they share one stamp)."""
        if len(self._stamps) < 2:
            return None
        p = (self._stamps[-1] - self._stamps[0]) / (len(self._stamps) - 1)
        return p if p > 1e-3 else None

    def tick(self, stamp: float) -> None:
        self._stamps.append(stamp)

    def clear(self) -> None:
        self._stamps.clear()


def step_times(c: SlamConfig, gap: float, period: float | None) -> tuple[float, float]:
    """(dt for the odometry-rate test, data gap for window widening) of a scan ``gap`` s after the previous
    one in a stream whose mean period is ``period``: the rate is judged over at least one mean period
    (burst stamps), and a gap counts only past ``GAP_PERIODS`` mean periods (and ``wide_step_gap_s``)."""
    if period is None:  # the first scans of a stream: assume the common 10 Hz until the clock knows better
        return max(gap, DEFAULT_PERIOD_S), gap
    return max(gap, period), (gap if gap > GAP_PERIODS * period else 0.0)


def search_windows(c: SlamConfig, dist: float, rot: float, gap: float) -> StepWindows:
    """Windows for a scan ``dist`` m / ``rot`` rad (odometry) from the last node and ``gap`` s after the
    previous scan. Normal steps keep the configured windows (no extra cost); a wide step grows them by
    ``window_growth`` per m / rad plus ``window_growth_gap`` per s, bounded by ``max_search_window_*``."""
    rot = abs(rot)
    if dist <= c.wide_step_distance and rot <= c.wide_step_heading and gap <= c.wide_step_gap_s:
        return StepWindows(c.search_window_xy, c.search_window_theta, False)
    g = max(gap, 0.0) * c.window_growth_gap
    xy = min(max(c.max_search_window_xy, c.search_window_xy), c.search_window_xy + c.window_growth * dist + g)
    th = min(max(c.max_search_window_theta, c.search_window_theta),
             c.search_window_theta + c.window_growth * rot + g)
    return StepWindows(xy, th, True)


def suspect_step(c: SlamConfig, dist: float, rot: float, dt: float) -> bool:
    """True when odometry moved faster than the robot plausibly can between two scans (``dt`` s apart;
    a non-positive ``dt`` counts as one 10 Hz period)."""
    period = dt if dt > 1e-3 else 0.1
    return dist > c.max_odom_rate_distance * period or abs(rot) > c.max_odom_rate_heading * period


def unmatched_sigmas(c: SlamConfig, dist: float, rot: float, gap: float) -> tuple[float, float]:
    """(xy, theta) std dev of the odometry edge of a wide step that could not be matched: large, so the
    graph bends there first when a loop closure disagrees."""
    extra = c.window_growth_gap * max(gap, 0.0)
    return (c.odom_sigma_xy + c.unmatched_sigma_growth * dist + extra,
            c.odom_sigma_theta + c.unmatched_sigma_growth * abs(rot) + extra)


def legacy_jump(c: SlamConfig, dist: float, rot: float) -> bool:
    """The old guard (``drop_odom_jumps``): a step beyond ``max_odom_jump_*`` is dropped."""
    return dist > c.max_odom_jump_distance or abs(rot) > c.max_odom_jump_heading


def loop_radius(c: SlamConfig, drift_sigma: float) -> float:
    """Loop-candidate search radius: the fixed radius plus 3 sigma of the position uncertainty accrued since
    the last loop closure (a long unmatched stretch may have drifted further), bounded."""
    r = c.loop_search_radius + 3.0 * max(drift_sigma, 0.0)
    return min(max(c.loop_search_radius, c.loop_search_radius_max), r) if math.isfinite(r) else c.loop_search_radius


def loop_windows(c: SlamConfig, drift_xy: float, drift_theta: float) -> StepWindows:
    """Loop-match search windows: the configured ones plus 3 sigma of the position / heading uncertainty
    accrued since the last loop closure, bounded by ``loop_search_window_*_max``.

    A candidate found by the widened radius is only useful if the correlative search can reach where the
    robot really is: after a long stretch the scans could not pin down, the pose may be off by more than
    the fixed window. A run that matched every step keeps the fixed window (and its cost)."""
    def grow(base: float, cap: float, sigma: float) -> float:
        w = base + 3.0 * max(sigma, 0.0)
        return min(max(base, cap), w) if math.isfinite(w) else base

    xy = grow(c.loop_search_window_xy, c.loop_search_window_xy_max, drift_xy)
    th = grow(c.loop_search_window_theta, c.loop_search_window_theta_max, drift_theta)
    return StepWindows(xy, th, xy > c.loop_search_window_xy or th > c.loop_search_window_theta)
