"""The bounded scan queue between the DDS callback and the SLAM worker.

The callback must never block on SLAM work, so scans wait here; when the worker falls behind by more
than ``size`` scans the OLDEST waiting one is dropped (the newest scan is the one worth having: the
robot is where it says). Every drop is counted and the deepest the queue ever got is kept, because
"0 scans dropped, at most N waiting" is the claim the status and the benches have to show. Each scan
carries its arrival time so the worker can report how long a scan waited before being processed.
"""

from __future__ import annotations

import collections
import threading
import time
from typing import Generic, TypeVar

T = TypeVar("T")


class ScanQueue(Generic[T]):
    """Thread-safe drop-oldest FIFO of at most ``size`` items, with drop and high-water counters."""

    def __init__(self, size: int) -> None:
        if size < 1:
            raise ValueError(f"queue size must be >= 1, got {size}")
        self.size = size
        self._items: collections.deque[tuple[float, T]] = collections.deque()
        self._cv = threading.Condition()
        self.dropped = 0  # items pushed out by newer ones while the worker was behind
        self.high_water = 0  # the most items ever waiting at once
        self._taken = 0  # items handed out by get() whose done() has not come yet

    def put(self, item: T) -> bool:
        """Queue ``item`` (arrival = now, monotonic); True when the oldest waiting item had to be dropped."""
        with self._cv:
            dropped = len(self._items) >= self.size
            if dropped:
                self._items.popleft()
                self.dropped += 1
            self._items.append((time.monotonic(), item))
            self.high_water = max(self.high_water, len(self._items))
            self._cv.notify()
        return dropped

    def get(self, timeout: float) -> tuple[float, T] | None:
        """The oldest waiting (arrival time, item), waiting up to ``timeout`` s for one; None if none came."""
        with self._cv:
            if not self._items:
                self._cv.wait(timeout)
            if not self._items:
                return None
            self._taken += 1
            return self._items.popleft()

    def done(self) -> None:
        """The worker finished an item from :meth:`get` (processed, skipped or failed)."""
        with self._cv:
            self._taken -= 1

    def pending(self) -> int:
        """Items waiting or taken and not done yet: 0 means every item put has been dealt with."""
        with self._cv:
            return len(self._items) + self._taken

    def clear(self) -> int:
        """Drop everything waiting (not counted as a drop: pausing discards on purpose); returns how many."""
        with self._cv:
            n = len(self._items)
            self._items.clear()
            return n

    def wake(self) -> None:
        """Wake a worker blocked in :meth:`get` (shutdown)."""
        with self._cv:
            self._cv.notify_all()

    def __len__(self) -> int:
        with self._cv:
            return len(self._items)
