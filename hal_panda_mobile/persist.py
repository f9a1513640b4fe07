"""A restarted simulator continues the run it replaces: same sim clock, same robot pose, same odometry.

Why (issue 37 item 1): a HAL killed mid-goal and restarted by ``rbnx boot`` used to start again at sim
t = 0 at the scene's start pose. Navigation only trusts a /clock newer than the last it saw, so it
stalled; once the new clock passed the old one it judged the goal reached from the *old* TF (stamped in
the "future" of the new clock) while the real robot stood 7 m away, and SLAM glued the new world onto the
old map. A real base does not teleport when its driver restarts, so the simulator must not either.

The loop hands the sim's state (:meth:`PandaMobileSim.resume_state`) to :class:`SimContinuity` every
``period_s`` of sim time; it is written to ``<RBNX_RUN_DIR>/<instance>-sim.json`` with the published clock
and a fingerprint of the CMD_INIT config. A restart (``RBNX_RESTARTS`` > 0) with the same config resumes
it: the base at rest where it was, odometry where it was, and the clock a little *ahead* of the last one
published (``period_s`` + margin), so every consumer sees time go on and TF stamps stay monotonic. A
first start discards any file left by an earlier run.
"""

from __future__ import annotations

import hashlib
import json
import logging
import time
from typing import Any

from hal_panda_mobile.sim import PandaMobileSim, SimConfigError
from robonix_api.runstate import StateFile

log = logging.getLogger("hal_panda_mobile.persist")
PERIOD_S = 0.1  # sim s between saved states: the most a resumed run loses (a few cm of motion)
MARGIN_S = 0.05  # sim s the resumed clock starts past the last one that can have been published


def fingerprint(config: dict[str, Any]) -> str:
    """Identifies the CMD_INIT config: a state is only resumed into the same scene, robot and settings."""
    text = json.dumps(config, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


class SimContinuity:
    """Saves the running sim's state and, once per process, resumes it after a crash-restart."""

    def __init__(self, file: StateFile, config_fp: str, period_s: float = PERIOD_S) -> None:
        self.file, self.fp, self.period_s = file, config_fp, period_s
        self._due = -1.0
        self.writes = 0

    @classmethod
    def for_instance(cls, instance_id: str, config: dict[str, Any]) -> SimContinuity:
        return cls(StateFile.for_instance(instance_id, "sim"), fingerprint(config))

    def resume_into(self, sim: PandaMobileSim, allowed: bool) -> str:
        """Restore the saved run into a freshly built ``sim`` when ``allowed`` (a restart, first session of
        the process) and the config matches; else discard the file. Returns what happened, for the log."""
        doc = self.file.read() if allowed else None
        if doc is None or doc.get("fingerprint") != self.fp:
            why = ("not a restart" if not allowed else "no saved state" if doc is None
                   else "saved state is of another config")
            self.file.discard()
            return f"fresh start at sim t=0 ({why})"
        try:
            sim.restore(doc["state"], min_time=float(doc["published_t"]) + self.period_s + MARGIN_S)
        except (SimConfigError, KeyError, TypeError, ValueError) as exc:
            self.file.discard()
            return f"fresh start at sim t=0 (saved state unusable: {exc})"
        x, y, yaw = doc["state"]["true"]
        return (f"resumed the crashed run at sim t={sim.time:.3f} (saved {time.time() - float(doc['wall']):.1f} s "
                f"ago), base at ({x:.2f}, {y:.2f}, {yaw:.2f})")

    def maybe_save(self, sim: PandaMobileSim, published_t: float) -> dict[str, Any] | None:
        """The document to write when ``period_s`` of sim time passed since the last one (call under the sim
        lock: it reads the sim); None otherwise. ``write`` it outside the lock."""
        if sim.time < self._due:
            return None
        self._due = sim.time + self.period_s
        return {"fingerprint": self.fp, "published_t": published_t, "wall": time.time(),
                "state": sim.resume_state()}

    def write(self, doc: dict[str, Any]) -> None:
        self.file.write(doc)
        self.writes += 1

    def discard(self) -> None:
        """A clean shutdown: nothing to resume."""
        self.file.discard()
