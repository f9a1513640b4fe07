"""Quality metrics for tests and the benchmark: trajectory error and map overlap."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from robonix_common.grid import GridMap


def align_se2(est: ArrayLike, gt: ArrayLike) -> np.ndarray:
    """Rigid 2D transform (x, y, theta) that best maps ``est`` positions onto ``gt`` (least squares)."""
    a = np.asarray(est, dtype=float)[:, :2]
    b = np.asarray(gt, dtype=float)[:, :2]
    ma, mb = a.mean(axis=0), b.mean(axis=0)
    h = (a - ma).T @ (b - mb)
    th = math.atan2(h[0, 1] - h[1, 0], h[0, 0] + h[1, 1])
    c, s = math.cos(th), math.sin(th)
    t = mb - np.array([[c, -s], [s, c]]) @ ma
    return np.array([t[0], t[1], th])


def ate_rmse(est: ArrayLike, gt: ArrayLike, *, align: bool = False) -> float:
    """Absolute trajectory error (RMSE of position, m).

    ``align=False`` compares in the common start frame (SLAM's map frame starts at the first odometry
    pose, which our synthetic drives put at the ground-truth start); that is stricter than aligning,
    which hides a constant offset/rotation. ``align=True`` first applies the best rigid SE(2) alignment.
    """
    e = np.asarray(est, dtype=float).reshape(-1, 3)
    g = np.asarray(gt, dtype=float).reshape(-1, 3)
    if e.shape != g.shape or len(e) == 0:
        raise ValueError(f"trajectories must have the same non-zero length, got {e.shape} and {g.shape}")
    p = e[:, :2]
    if align:
        x, y, th = align_se2(e, g)
        c, s = math.cos(th), math.sin(th)
        p = p @ np.array([[c, -s], [s, c]]).T + [x, y]
    return float(np.sqrt(np.mean(np.sum((p - g[:, :2]) ** 2, axis=1))))


def occupied_iou(est: GridMap, gt: GridMap, *, tolerance_cells: int = 1, observed_only: bool = False) -> float:
    """IoU of occupied cells with a tolerance, on the ground truth's raster.

    Estimated occupied cells are resampled (by cell centre) onto ``gt``'s grid. A cell of either set
    counts as matched if the other set has an occupied cell within ``tolerance_cells`` (Chebyshev), so a
    wall surface detected one cell off (hits land on the boundary of the wall raster) is not an error:
    I = (|E ∩ dil(G)| + |G ∩ dil(E)|) / 2, IoU = I / (|E| + |G| - I); with tolerance 0 this is the plain IoU.
    ``observed_only`` drops ground-truth cells that the estimate never observed (no known cell within
    the tolerance): walls the robot could never see should not count as misses.
    """
    if abs(est.origin_yaw) > 1e-9 or abs(gt.origin_yaw) > 1e-9:
        raise ValueError("occupied_iou supports axis-aligned grids only (origin_yaw == 0)")
    r, c = np.nonzero(est.data >= 65)
    x, y = est.cell_to_world(c, r)
    gc, gr = gt.world_to_cell(x, y)
    inside = gt.in_bounds(gc, gr)
    e = np.zeros(gt.data.shape, dtype=bool)
    e[gr[inside], gc[inside]] = True
    g = gt.data >= 65
    from scipy import ndimage  # evaluation only: not loaded by the service's start-up

    k = 2 * tolerance_cells + 1
    st = np.ones((k, k), dtype=bool)
    if observed_only:
        r2, c2 = np.nonzero(est.data >= 0)
        x2, y2 = est.cell_to_world(c2, r2)
        kc, kr = gt.world_to_cell(x2, y2)
        ok = gt.in_bounds(kc, kr)
        known = np.zeros(gt.data.shape, dtype=bool)
        known[kr[ok], kc[ok]] = True
        g &= ndimage.binary_dilation(known, st)
    dil = (lambda m: ndimage.binary_dilation(m, st)) if tolerance_cells > 0 else (lambda m: m)
    inter = 0.5 * (np.count_nonzero(e & dil(g)) + np.count_nonzero(g & dil(e)))
    union = np.count_nonzero(e) + np.count_nonzero(g) - inter
    outside = int(np.count_nonzero(~inside))  # estimated walls beyond the ground-truth raster are errors
    return float(inter / (union + outside)) if union + outside > 0 else 1.0
