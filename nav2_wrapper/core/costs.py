"""Nav2 cost values and the inflation cost function, kept in one place so every module agrees."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

FREE = 0
INSCRIBED = 253
LETHAL = 254
NO_INFORMATION = 255
MAX_NON_OBSTACLE = 252


def inflation_cost(dist_m: NDArray[np.float64] | float, inscribed_radius: float, inflation_radius: float,
                   cost_scaling_factor: float) -> NDArray[np.uint8]:
    """Nav2 InflationLayer::computeCost for distances (m) to the nearest lethal cell.

    0 → lethal, ≤ inscribed radius → inscribed, ≤ inflation radius →
    252·exp(−k·(d − r_inscribed)) (truncated like Nav2's cast), beyond → free.
    """
    d = np.asarray(dist_m, dtype=np.float64)
    out = np.zeros(d.shape, dtype=np.uint8)
    decay = np.floor(MAX_NON_OBSTACLE * np.exp(-cost_scaling_factor * (d - inscribed_radius)))
    band = (d > inscribed_radius) & (d <= inflation_radius)
    out[band] = np.clip(decay[band], 0, MAX_NON_OBSTACLE).astype(np.uint8)
    out[d <= inscribed_radius] = INSCRIBED
    out[d <= 0.0] = LETHAL
    return out


def distance_from_cost(cost: float, inscribed_radius: float, cost_scaling_factor: float) -> float:
    """Invert the decay: the (approximate) distance to the nearest obstacle implied by an inflated cost."""
    if cost >= INSCRIBED:
        return 0.0 if cost >= LETHAL else inscribed_radius
    if cost <= 0:
        return float("inf")
    return inscribed_radius - float(np.log(cost / MAX_NON_OBSTACLE)) / cost_scaling_factor
