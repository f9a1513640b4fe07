"""A one-goal journal: a navigation process restarted after a crash picks up the goal it was driving.

The running goal (run id and map-frame pose) is written atomically to ``$RBNX_RUN_DIR/<id>-goal.json``
when accepted and removed when it ends in any way, including a clean shutdown; only a process that died
mid-goal leaves it behind. Without ``RBNX_RUN_DIR`` (not under ``rbnx boot``) nothing is written.
"""

from __future__ import annotations

import json
import logging
import os
from dataclasses import dataclass
from pathlib import Path

log = logging.getLogger("nav2_wrapper.journal")


@dataclass(frozen=True)
class JournaledGoal:
    run_id: str
    x: float
    y: float
    yaw: float


class GoalJournal:
    def __init__(self, path: Path | None) -> None:
        self.path = path

    @classmethod
    def from_env(cls, instance_id: str) -> GoalJournal:
        run_dir = os.environ.get("RBNX_RUN_DIR", "").strip()
        return cls(Path(run_dir) / f"{instance_id}-goal.json" if run_dir else None)

    def record(self, goal: JournaledGoal) -> None:
        if self.path is None:
            return
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            tmp = self.path.with_suffix(".tmp")
            tmp.write_text(json.dumps(goal.__dict__))
            os.replace(tmp, self.path)
        except OSError as exc:  # a journal is a convenience: never fail a goal over it
            log.warning("cannot write the goal journal %s: %s", self.path, exc)

    def clear(self) -> None:
        if self.path is not None:
            try:
                self.path.unlink(missing_ok=True)
            except OSError as exc:
                log.warning("cannot remove the goal journal %s: %s", self.path, exc)

    def pending(self) -> JournaledGoal | None:
        """The goal a previous process of this id was driving when it died, if any."""
        if self.path is None or not self.path.is_file():
            return None
        try:
            d = json.loads(self.path.read_text())
            return JournaledGoal(str(d["run_id"]), float(d["x"]), float(d["y"]), float(d["yaw"]))
        except (OSError, ValueError, KeyError, TypeError) as exc:
            log.warning("ignoring an unreadable goal journal %s: %s", self.path, exc)
            return None
