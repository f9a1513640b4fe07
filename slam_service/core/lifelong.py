"""Lifelong mapping: which old nodes a new node makes redundant.

A robot that works all day drives the same rooms again and again. Keeping every node makes the pose
graph, the node scans, the optimiser's matrices, the loop-closure submaps and the saved session grow
with the distance driven. Here a node is redundant once a newer node stands at nearly the same pose
(position and heading) and sees nearly the same thing (most of the old scan's endpoints lie next to the
new scan's): the old one adds nothing to the map the newer one does not, and the newer one reflects the
world as it is now. The engine removes the redundant node (un-rendering its scan, reconnecting its edges
through :meth:`PoseGraph.remove_node`), so node count is bounded by the mapped area times the headings
the robot drives it at.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from robonix_common.geometry import transform_points

from .types import SlamConfig


def redundant_nodes(config: SlamConfig, poses: NDArray, stamps: Sequence[float], points: Sequence[NDArray],
                    k: int, protect_from: int) -> list[int]:
    """Old nodes that node ``k`` makes redundant, oldest first (at most ``prune_max_per_node``).

    Only nodes in ``1 .. protect_from - 1`` are considered: node 0 anchors the map frame, and the recent
    chain (the running submap) must stay intact for sequential matching.
    """
    c = config
    if protect_from <= 1:
        return []
    cand = np.arange(1, min(protect_from, len(poses)))
    d = np.hypot(*(poses[cand, :2] - poses[k, :2]).T)
    dth = np.abs(np.remainder(poses[cand, 2] - poses[k, 2] + np.pi, 2 * np.pi) - np.pi)
    near = cand[(d <= c.prune_distance) & (dth <= c.prune_heading)]
    if len(near) == 0:
        return []
    near = near[np.argsort(np.asarray(stamps, dtype=float)[near], kind="stable")]
    from scipy.spatial import cKDTree  # scipy is loaded by the first scan match already

    tree = cKDTree(transform_points(poses[k], points[k]))
    out: list[int] = []
    for m in near:
        if overlap(tree, transform_points(poses[m], points[m]), c.prune_overlap_distance) >= c.prune_min_overlap:
            out.append(int(m))
            if len(out) >= c.prune_max_per_node:
                break
    return out


def overlap(tree: object, pts: NDArray, distance: float) -> float:
    """Fraction of ``pts`` within ``distance`` of the points indexed by ``tree`` (a cKDTree)."""
    if len(pts) == 0:
        return 0.0
    d, _ = tree.query(pts, k=1, distance_upper_bound=distance)  # type: ignore[attr-defined]
    return float(np.mean(np.isfinite(d)))
