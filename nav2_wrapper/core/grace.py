"""Pause, grace and fail: what a running goal does while an input it depends on is gone.

A provider that crashes and is restarted, or stalls for a few seconds, should not cost the goal: the
robot stops at once, the goal stays RUNNING ("waiting for mapping"), and it carries on when the input
returns within ``input_grace_s``. Only an input that stays away longer fails the goal, with a reason
naming it. Optional inputs (the lidar for the obstacle layer) never pause: they only degrade.

Pure bookkeeping over (time, {input: why}) so it is unit-tested without DDS; the provider decides what
"lost" means (DDS liveliness, the atlas' TERMINATED notice, stale data).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

OK, PAUSED, FAILED = "OK", "PAUSED", "FAILED"


@dataclass(frozen=True)
class Verdict:
    state: str                 # OK | PAUSED | FAILED
    detail: str = ""           # PAUSED: "waiting for mapping (...)"; FAILED: the reason
    resumed: bool = False      # OK after a pause: the caller replans and resets progress checks


@dataclass
class InputGrace:
    """Tracks since when each required input is lost; grace counts on both clocks given to ``update``.

    ``update(now, wall, lost)``: ``now`` is the provider's clock (sim time), ``wall`` a monotonic wall
    clock. The grace ends when *both* have advanced ``grace_s`` since the input was lost, so a fast
    simulator does not shorten the time a restart gets, and a slow one does not either. (A stalled
    sim clock is handled by the provider's clock timeout, which fails the goal on its own.)
    """

    grace_s: float = 5.0
    _since: dict[str, tuple[float, float]] = field(default_factory=dict)
    _paused: bool = False

    def reset(self) -> None:
        self._since.clear()
        self._paused = False

    @property
    def paused(self) -> bool:
        return self._paused

    def update(self, now: float, wall: float, lost: Mapping[str, str], clock_stalled: bool = False) -> Verdict:
        for name in list(self._since):
            if name not in lost:
                del self._since[name]
        for name in lost:
            self._since.setdefault(name, (now, wall))
        if not lost:
            was, self._paused = self._paused, False
            return Verdict(OK, resumed=was)
        waited = {n: (wall - w0) if clock_stalled else min(now - t0, wall - w0)
                  for n, (t0, w0) in self._since.items()}
        worst = max(waited, key=lambda n: waited[n])
        if waited[worst] > self.grace_s:
            self._paused = False
            return Verdict(FAILED, f"{worst} lost: {lost[worst]} (not back within input_grace_s="
                                   f"{self.grace_s:g} s)")
        self._paused = True
        names = sorted(lost)
        why = lost[names[0]] if len(names) == 1 else "; ".join(f"{n}: {lost[n]}" for n in names)
        left = max(0.0, self.grace_s - waited[worst])
        return Verdict(PAUSED, f"waiting for {', '.join(names)} ({why}); robot stopped, "
                               f"goal fails in {left:.1f} s unless it returns")
