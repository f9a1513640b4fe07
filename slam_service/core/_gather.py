"""numba kernel for the correlative matcher: sums of a field over shifted beam endpoints.

numpy did this as a fancy-index gather of a (T, P, B) array followed by a sum: ~300 000 scattered loads
per scan and as many temporaries, a third of a match. The loop sums in the same order (beam by beam,
in float32), so the scores are bit-identical to the numpy version.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def shifted_sums(field, flat, rows, offsets):  # pragma: no cover - compiled
    """out[k, j] = sum over beams p of field[flat[rows[k], p] + offsets[k, j]] (float32, p in order).

    ``field`` is a flattened lookup, ``flat`` (T, P) the endpoints' flat indices per heading, ``rows`` (K,)
    the heading of each output row and ``offsets`` (K, J) the flat shifts scored for it."""
    k_n, j_n = offsets.shape
    p_n = flat.shape[1]
    out = np.zeros((k_n, j_n), np.float32)
    for k in range(k_n):
        fr = flat[rows[k]]
        for j in range(j_n):
            off = offsets[k, j]
            acc = np.float32(0.0)
            for p in range(p_n):
                acc += field[fr[p] + off]
            out[k, j] = acc
    return out
