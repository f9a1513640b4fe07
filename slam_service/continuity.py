"""The last map→odom a mapping service published, kept for its crash-restarted successor.

Why (issue 33, crash point): the autosaved session is written every ``autosave_period_s`` (was 2 s); resuming
from it alone put map→odom where it was at the last autosaved node, while navigation had been driving on
the map→odom published up to the crash, corrected by every scan since. The difference (scan-matching
corrections, a loop closure) is a jump of the robot in the map the navigator sees, as if in a new world:
replans, recoveries, goals that derailed in 2 of 6 runs. This file holds the transform as last sent
(``<RBNX_RUN_DIR>/<instance>-map_to_odom.json``, rewritten at most every ``WRITE_PERIOD_S`` of wall time),
so the restarted service continues with exactly the frame navigation already uses.
"""

from __future__ import annotations

import math
import time

from robonix_api.runstate import StateFile

WRITE_PERIOD_S = 0.1  # wall s between writes (the transform changes at most once per scan)


class MapToOdomFile:
    def __init__(self, file: StateFile) -> None:
        self.file = file
        self._last_write = -math.inf

    @classmethod
    def for_instance(cls, instance_id: str) -> MapToOdomFile:
        return cls(StateFile.for_instance(instance_id, "map_to_odom"))

    def note(self, m2o: tuple[float, float, float], stamp: float) -> None:
        """The transform just published (throttled to ``WRITE_PERIOD_S``)."""
        now = time.monotonic()
        if now - self._last_write < WRITE_PERIOD_S:
            return
        self._last_write = now
        self.file.write({"map_to_odom": [float(v) for v in m2o], "stamp": float(stamp)})

    def last(self) -> tuple[float, float, float] | None:
        """The transform the previous process published last, or None (none, unreadable, not finite)."""
        doc = self.file.read()
        try:
            x, y, th = (float(v) for v in doc["map_to_odom"])  # type: ignore[index]
        except (TypeError, KeyError, ValueError):
            return None
        return (x, y, th) if all(math.isfinite(v) for v in (x, y, th)) else None

    def discard(self) -> None:
        self.file.discard()
