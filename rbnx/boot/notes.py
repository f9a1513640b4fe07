"""Print what a running package says about itself on the atlas (its lifecycle ``state_detail``), such as
the navigation planner's first-run warm-up, so a long wait after ``running`` is never silent.

One query per period (not per entry); a note is printed when it first appears, then at most every
``every_s`` seconds while it changes, and once more when it is gone.
"""

from __future__ import annotations

import sys
import time
from typing import Any

from rbnx.atlas_rpc import AtlasError

#: Details the atlas itself writes (heartbeat lapses, terminations): the supervisor reports those.
_OWN = ("heartbeat lapsed",)


class NoteWatch:
    def __init__(self, period_s: float = 1.0, every_s: float = 10.0, out: Any = None) -> None:
        self.period_s, self.every_s = period_s, every_s
        self.out = out or sys.stdout
        self._next = 0.0
        self._shown: dict[str, tuple[str, float]] = {}  # entry -> (note, when printed)

    def poll(self, atlas: Any, names: list[str]) -> None:
        now = time.monotonic()
        if now < self._next:
            return
        self._next = now + self.period_s
        try:
            details = {p.id: p.state_detail for p in atlas.query()}
        except AtlasError:
            return
        for name in names:
            self._one(name, details.get(name, ""), now)

    def _one(self, name: str, note: str, now: float) -> None:
        note = "" if note.startswith(_OWN) else note
        last, when = self._shown.get(name, ("", 0.0))
        if note == last:
            return
        if not note:
            print(f"{name}: {last.split(' (', 1)[0]}: done", file=self.out, flush=True)
            self._shown.pop(name, None)
        elif not last or now - when >= self.every_s:
            print(f"{name}: {note}", file=self.out, flush=True)
            self._shown[name] = (note, now)
