"""Short reorder buffer: scans that arrive slightly out of stamp order are sorted, not skipped.

Real logs and busy transports deliver some scans late (hundreds in a 45-minute indoor log). Each scan is
held until the newest stamp seen is ``window`` s past it, then released in stamp order, so the engine's
output is delayed by at most the window. In adaptive mode nothing is held until the stream has delivered
its first late scan: in-order streams keep zero latency. Exact duplicates (same stamp, same ranges) are
reported so the caller can skip and count them.
"""

from __future__ import annotations

import heapq
import itertools
from collections import deque
from collections.abc import Hashable
from typing import Generic, Literal, TypeVar

T = TypeVar("T")
Verdict = Literal["ok", "late", "duplicate"]


class ReorderBuffer(Generic[T]):
    """Holds ``(stamp, item)``; :meth:`push` says whether the item was accepted and returns what is due."""

    def __init__(self, window: float, adaptive: bool = True, memory: int = 64) -> None:
        self.window = float(window)
        self.holding = not adaptive and self.window > 0
        self._heap: list[tuple[float, int, T]] = []
        self._seq = itertools.count()
        self._newest = -float("inf")
        self._released = -float("inf")  # stamp of the last released item
        self._recent: deque[tuple[float, Hashable]] = deque(maxlen=memory)

    def __len__(self) -> int:
        return len(self._heap)

    def push(self, stamp: float, item: T, key: Hashable = None) -> tuple[Verdict, list[tuple[float, T]]]:
        """Offer one item. ``key`` identifies its content (exact-duplicate test together with the stamp)."""
        if key is not None:
            if (stamp, key) in self._recent:
                return "duplicate", []
            self._recent.append((stamp, key))
        if stamp < self._released:
            if self.holding or self.window <= 0 or stamp < self._released - self.window:
                return "late", []
            self.holding = True  # first late scan of an in-order stream: sort from now on (this one is lost)
            return "late", []
        if not self.holding:
            self._released = stamp
            self._newest = max(self._newest, stamp)
            return "ok", [(stamp, item)]
        heapq.heappush(self._heap, (stamp, next(self._seq), item))
        self._newest = max(self._newest, stamp)
        return "ok", self._due(self._newest - self.window)

    def flush(self) -> list[tuple[float, T]]:
        """Release everything held, in stamp order."""
        return self._due(float("inf"))

    def _due(self, upto: float) -> list[tuple[float, T]]:
        out = []
        while self._heap and self._heap[0][0] <= upto:
            stamp, _, item = heapq.heappop(self._heap)
            self._released = stamp
            out.append((stamp, item))
        return out
