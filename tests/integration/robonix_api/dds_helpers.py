"""Helpers shared by the DDS tests."""

from __future__ import annotations

import subprocess
import time
from collections.abc import Callable


def stop_process(proc: subprocess.Popen) -> None:
    """Stop one child by its PID: SIGTERM, then SIGKILL if it does not exit in time."""
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(timeout=15)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(timeout=15)


def poll(pred: Callable[[], object], timeout: float = 20.0, every: float = 0.02) -> bool:
    """True as soon as pred() holds; generous deadline, independent of machine speed."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if pred():
            return True
        time.sleep(every)
    return bool(pred())
