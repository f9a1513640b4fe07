"""The provider's scan queue: drop-oldest beyond its size, every drop counted, the deepest backlog kept."""

from __future__ import annotations

import threading

import pytest
from support.wait import wait_until

from slam_service.scan_queue import ScanQueue


def test_overflow_drops_the_oldest_and_counts() -> None:
    q: ScanQueue[int] = ScanQueue(4)
    dropped = [q.put(i) for i in range(10)]
    assert dropped == [False] * 4 + [True] * 6
    assert (q.dropped, q.high_water, len(q)) == (6, 4, 4)
    got = [q.get(0.0) for _ in range(5)]
    assert [g[1] for g in got if g is not None] == [6, 7, 8, 9]  # the newest survive, in order
    assert got[-1] is None
    first = ScanQueue[str](1)
    first.put("a")
    item = first.get(0.0)
    assert item is not None
    assert item[0] > 0  # arrival time (monotonic) travels with the item


def test_clear_is_not_a_drop_and_size_is_validated() -> None:
    q: ScanQueue[int] = ScanQueue(3)
    for i in range(2):
        q.put(i)
    assert q.clear() == 2
    assert (q.dropped, q.high_water, len(q)) == (0, 2, 0)
    with pytest.raises(ValueError, match="size"):
        ScanQueue(0)


def test_a_waiting_consumer_gets_each_item_once() -> None:
    q: ScanQueue[int] = ScanQueue(1000)
    seen: list[int] = []
    stop = threading.Event()

    def consume() -> None:
        while not stop.is_set():
            item = q.get(0.05)
            if item is not None:
                seen.append(item[1])

    th = threading.Thread(target=consume, daemon=True)
    th.start()
    for i in range(500):
        q.put(i)
    wait_until(lambda: len(seen) == 500, timeout_s=30, what="the consumer drained the queue")
    stop.set()
    q.wake()
    th.join(5)
    assert seen == list(range(500))
    assert q.dropped == 0


def test_pending_counts_taken_items_until_done() -> None:
    """An item the worker took is still pending until done(): what SlamLoop.idle() builds on."""
    q: ScanQueue[int] = ScanQueue(4)
    assert q.pending() == 0
    q.put(1)
    q.put(2)
    assert q.pending() == 2
    assert q.get(0.0) is not None
    assert (len(q), q.pending()) == (1, 2)   # taken, not done: still pending
    q.done()
    assert q.pending() == 1
    assert q.get(0.0) is not None
    q.done()
    assert q.get(0.0) is None                # nothing handed out: nothing to be done with
    assert q.pending() == 0
