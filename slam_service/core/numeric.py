"""Load the scipy parts the engine uses (distance transforms, k-d trees, sparse solves) ahead of need.

The engine imports them where they are used, so a provider process starts (and registers) without
paying for them; the provider calls :func:`load_numeric_stack` on a background thread once its inputs
exist, so the first scan and the first loop closure do not pay for them either.
"""

from __future__ import annotations


def load_numeric_stack() -> None:
    import scipy.ndimage  # noqa: F401
    import scipy.sparse.linalg  # noqa: F401
    import scipy.spatial  # noqa: F401
