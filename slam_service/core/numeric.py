"""Load the scipy parts the engine uses (distance transforms, k-d trees, sparse solves) ahead of need.

The engine imports them where they are used, so a provider process starts (and registers) without
paying for them while its upstream providers start too; the provider calls
:func:`load_in_background` at its first CMD_INIT (answered ``Deferred`` until the lidar exists), so the
import overlaps the wait and the first scan does not pay for it.
"""

from __future__ import annotations

import threading

_started: list[threading.Thread] = []
_lock = threading.Lock()


def load_numeric_stack() -> None:
    import scipy.ndimage
    import scipy.sparse.linalg
    import scipy.spatial  # noqa: F401


def load_in_background() -> threading.Thread:
    """Start :func:`load_numeric_stack` on a daemon thread, once per process."""
    with _lock:
        if not _started:
            _started.append(threading.Thread(target=load_numeric_stack, name="scipy-load", daemon=True))
            _started[0].start()
        return _started[0]
