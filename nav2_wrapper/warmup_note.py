"""Say that the planner is warming up, while it does: no silent minutes on a machine's first run.

numba compiles the planner's kernels the first time they run on a machine (cached afterwards). The
provider starts that compile at its first CMD_INIT (:func:`nav2_wrapper.core.warmup.compile_in_background`);
this module times it and tells people: the atlas shows the note next to the provider's state (``rbnx
boot`` prints it), and a goal accepted meanwhile stays PENDING with the note as its detail, so clients
(``rbnx navigate``/``rbnx demo``) start their timeout only once it is gone (:data:`WARMING`).
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable

from nav2_wrapper.core.warmup import compile_in_background, ready, wait_finished

log = logging.getLogger("nav2_wrapper")

#: Every warm-up note starts with this; clients recognise a PENDING goal that waits for it by the prefix.
WARMING = "warming up the planner"
#: What a cold compile took on the 2-core reference machine (bench/kernel_compile.py); only for the note.
COLD_COMPILE_ESTIMATE_S = 20
REPORT_PERIOD_S = 2.0

_t0: list[float] = []
_lock = threading.Lock()


def warming() -> bool:
    """The compile thread runs (started, not finished)."""
    return bool(_t0) and not wait_finished(0)


def note() -> str:
    """``warming up the planner (compiling navigation kernels, first run on this machine: ~20 s): 12 s so far``."""
    elapsed = time.monotonic() - _t0[0] if _t0 else 0.0
    return (f"{WARMING} (compiling navigation kernels, first run on this machine: ~{COLD_COMPILE_ESTIMATE_S} s): "
            f"{elapsed:.0f} s so far")


def start(publish: Callable[[str], None] | None = None) -> None:
    """Start the background compile (once per process) and, when ``publish`` is given, a reporter that
    publishes :func:`note` every few seconds while it runs and "" when it ended (no note when the kernels
    load from the cache within the first period)."""
    with _lock:
        if _t0:
            return
        _t0.append(time.monotonic())
    compile_in_background()
    if publish is not None:
        threading.Thread(target=_report, args=(publish,), name="warmup-note", daemon=True).start()


def _report(publish: Callable[[str], None]) -> None:
    shown = False
    while not wait_finished(REPORT_PERIOD_S):
        publish(note())
        shown = True
    took = time.monotonic() - _t0[0]
    if shown:
        publish("")
        log.info("planner warm-up %s in %.0f s", "done" if ready() else "failed", took)
