"""The suite's one way to wait: poll a condition until it holds or a deadline passes.

Tests never sleep a fixed time and then assert; they wait for the event itself (or for a counter that
proves enough happened), with a deadline generous enough for a loaded two-core machine. No pytest and no
project imports in here, so unit tests, integration tests and the bench scripts can all use it.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TypeVar

T = TypeVar("T")


def wait_until(pred: Callable[[], T], timeout_s: float = 30.0, what: str | Callable[[], str] = "condition",
               interval: float = 0.05) -> T:
    """Poll ``pred`` every ``interval`` s until it returns something truthy, and return that value.

    Raises AssertionError after ``timeout_s`` naming ``what`` (a callable is called then, so the message
    can show the state at the deadline). ``pred`` is always tried once more after the deadline, so a slow
    machine that gets there just in time is not a failure.
    """
    deadline = time.monotonic() + timeout_s
    while True:
        value = pred()
        if value:
            return value
        if time.monotonic() > deadline:
            value = pred()
            if value:
                return value
            raise AssertionError(f"timed out after {timeout_s} s waiting for {what() if callable(what) else what}")
        time.sleep(interval)
