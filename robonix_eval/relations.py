"""Kuemmerle et al.'s relation metric ("On measuring the accuracy of SLAM algorithms", 2009).

A relations file lists ``t1 t2 dx dy dz roll pitch yaw``: the true motion of the robot from the scan at
t1 to the scan at t2, in the robot frame of t1. The error of one relation is ``ref^-1 * est`` of the
estimated relative motion; the metric is the mean (and std) of its translation norm and |rotation|
over all relations. Unlike ATE it needs no global ground truth and does not depend on the map frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from robonix_common.geometry import compose, relative


@dataclass(frozen=True)
class RelationScore:
    n: int  # relations scored
    missing: int  # relations whose stamps have no scan pose
    trans_mean: float  # m
    trans_std: float
    rot_mean: float  # rad
    rot_std: float
    trans_p95: float
    trans_max: float

    def to_dict(self) -> dict[str, float | int]:
        d = dict(self.__dict__)
        d["rot_mean_deg"] = math.degrees(self.rot_mean)
        d["rot_std_deg"] = math.degrees(self.rot_std)
        return d


def read_relations(path: str | Path) -> NDArray[np.float64]:
    """(R, 5) array of t1, t2, dx, dy, dyaw."""
    rows = []
    for lineno, line in enumerate(Path(path).read_text().splitlines(), 1):
        f = line.split()
        if not f:
            continue
        if len(f) < 8:
            raise ValueError(f"{Path(path).name}:{lineno}: relation needs 8 fields, got {len(f)}")
        rows.append([float(f[0]), float(f[1]), float(f[2]), float(f[3]), float(f[7])])
    return np.asarray(rows, dtype=float).reshape(-1, 5)


def scan_poses(node_stamps: NDArray, node_poses: NDArray, scan_stamps: NDArray, scan_odom: NDArray
               ) -> NDArray[np.float64]:
    """Pose of every scan: the node nearest in time, composed with the odometry motion from that node's
    scan to this one (the standard way to evaluate a motion-gated graph at every laser stamp)."""
    order = np.argsort(node_stamps, kind="stable")
    ns, npo = np.asarray(node_stamps)[order], np.asarray(node_poses)[order]
    odom_at = {float(t): o for t, o in zip(scan_stamps, scan_odom, strict=True)}
    node_odom = np.array([odom_at[float(t)] for t in ns])
    idx = np.clip(np.searchsorted(ns, scan_stamps), 1, len(ns) - 1) if len(ns) > 1 else np.zeros(len(scan_stamps),
                                                                                                    dtype=int)
    if len(ns) > 1:
        left = idx - 1
        idx = np.where(np.abs(scan_stamps - ns[left]) <= np.abs(ns[idx] - scan_stamps), left, idx)
    out = np.empty((len(scan_stamps), 3))
    for k, (j, o) in enumerate(zip(idx, scan_odom, strict=True)):
        out[k] = compose(npo[j], relative(node_odom[j], o))
    return out


def score_relations(relations: NDArray, stamps: NDArray, poses: NDArray, tol: float = 1e-3) -> RelationScore:
    """Score poses (one per stamp) against relations; a relation stamp must match a scan stamp within tol."""
    order = np.argsort(stamps, kind="stable")
    st, po = np.asarray(stamps)[order], np.asarray(poses)[order]

    def find(t: float) -> int:
        i = int(np.searchsorted(st, t))
        best = min((j for j in (i - 1, i) if 0 <= j < len(st)), key=lambda j: abs(st[j] - t), default=-1)
        return best if best >= 0 and abs(st[best] - t) <= tol else -1

    et, er = [], []
    missing = 0
    for t1, t2, dx, dy, dth in relations:
        i, j = find(t1), find(t2)
        if i < 0 or j < 0:
            missing += 1
            continue
        est = relative(po[i], po[j])
        e = relative(np.array([dx, dy, dth]), est)
        et.append(math.hypot(e[0], e[1]))
        er.append(abs(math.remainder(e[2], 2 * math.pi)))
    a, b = np.asarray(et), np.asarray(er)
    if len(a) == 0:
        return RelationScore(0, missing, *(float("nan"),) * 6)
    return RelationScore(len(a), missing, float(a.mean()), float(a.std()), float(b.mean()), float(b.std()),
                         float(np.percentile(a, 95)), float(a.max()))
