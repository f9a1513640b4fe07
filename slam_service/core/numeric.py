"""Load the scipy parts the engine uses (distance transforms, k-d trees, sparse solves) ahead of need.

The engine imports them where they are used, so a provider process starts (and registers) without
paying for them while its upstream providers start too; the provider calls
:func:`load_in_background` at its first CMD_INIT (answered ``Deferred`` until the lidar exists), so the
import overlaps the wait and the first scan does not pay for it.
"""

from __future__ import annotations

import threading

import numpy as np

_started: list[threading.Thread] = []
_lock = threading.Lock()


def load_numeric_stack() -> None:
    import scipy.ndimage
    import scipy.sparse.linalg
    import scipy.spatial  # noqa: F401

    from .occupancy import LogOddsGrid

    # the numba kernels (occupancy rays, lookup field, matcher sums): compiled (cold cache, ~1 s) or loaded
    LogOddsGrid(0.05).integrate(np.zeros(2), np.array([[1.0, 0.5], [-0.5, 1.0]]))
    from .lookup import LookupGrid
    from .matcher import match_scan

    # the lookup field's kernel, then the matcher's
    pts = np.array([[1.0, 0.5], [0.5, 1.0], [-1.0, 0.2], [0.3, -1.0], [-0.4, -0.6]])
    lookup = LookupGrid.from_points(pts, 0.05, 0.075, 0.8)
    match_scan(lookup, pts, np.zeros(3), window_xy=0.1, window_theta=0.02, angular_step=0.01, coarse_factor=2,
               refine=False)


def load_in_background() -> threading.Thread:
    """Start :func:`load_numeric_stack` on a daemon thread, once per process."""
    with _lock:
        if not _started:
            _started.append(threading.Thread(target=load_numeric_stack, name="scipy-load", daemon=True))
            _started[0].start()
        return _started[0]


if __name__ == "__main__":  # image build: ``python -m slam_service.core.numeric`` fills the numba cache
    load_numeric_stack()
