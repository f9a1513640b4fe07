"""The SLAM core's numba kernels, loaded off the scan path, with numpy twins used until they are.

Ray tracing (``_raycast``), the lookup field (``_field``) and the matcher's sums (``_gather``) compute
bit-identical results to the numpy code they replace, so which one runs never changes an output. That
lets the provider keep numba (~0.5-1 s of CPU to import and load, seconds to compile on a cold cache)
out of its boot: the first scans and the first /map, which the navigation provider waits for, use numpy,
and :func:`load_in_background` is started after the first map is published.

    python -c "from slam_service.core import kernels; kernels.load()"   # fill the numba cache (image build)
"""

from __future__ import annotations

import threading
import time

import numpy as np

_ready = threading.Event()
_started: list[threading.Thread] = []
_lock = threading.Lock()


def ready() -> bool:
    """True once the kernels are compiled or loaded in this process (until then callers use numpy)."""
    return _ready.is_set()


def load() -> float:
    """Import and run each kernel once on tiny inputs (compiles or loads from the cache); returns seconds."""
    t0 = time.perf_counter()
    from ._field import gaussian_field
    from ._gather import shifted_sums
    from ._raycast import add_scan

    add_scan(np.zeros((4, 4), np.float32), 0, 0, 0.01, 0.01, np.array([[0.16, 0.11]]), 0.05, np.float32(-0.4),
             np.float32(0.85), 0, 0, 4, 4)
    gaussian_field(np.array([1], np.int64), np.array([1], np.int64), 3, 3, 1.5, 20.25)
    shifted_sums(np.zeros(8, np.float32), np.zeros((1, 2), np.int64), np.zeros(1, np.int64), np.zeros((1, 1), np.int64))
    _ready.set()
    return time.perf_counter() - t0


def load_in_background() -> threading.Thread:
    """Start :func:`load` on a daemon thread, once per process."""
    with _lock:
        if not _started:
            _started.append(threading.Thread(target=load, name="slam-kernels", daemon=True))
            _started[0].start()
        return _started[0]

