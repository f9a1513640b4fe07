"""CARMEN reader and Kuemmerle relation scorer on a small synthetic log (no dataset needed)."""

from __future__ import annotations

import bz2
import math
from pathlib import Path

import numpy as np
import pytest

from robonix_common.geometry import compose, relative
from robonix_eval.carmen import CarmenError, read_carmen, to_scan
from robonix_eval.relations import read_relations, scan_poses, score_relations


def _write_log(path: Path, stamps: list[float], poses: np.ndarray) -> None:
    lines = ["# CARMEN log", "PARAM robot_front_laser_max 81.9 nohost 0"]
    for t, (x, y, th) in zip(stamps, poses, strict=True):
        ranges = " ".join(f"{2.0 + 0.01 * i:.2f}" for i in range(180))
        lines.append(f"FLASER 180 {ranges} {x} {y} {th} {x} {y} {th} {t:.6f} nohost 0.0")
        lines.append(f"ODOM {x} {y} {th} 0 0 0 {t:.6f} nohost 0.0")
    with bz2.open(path, "wt") as fh:
        fh.write("\n".join(lines) + "\n")


def test_reader_keeps_file_order_and_sorts_on_request(tmp_path: Path) -> None:
    poses = np.array([[0.0, 0, 0], [0.1, 0, 0.01], [0.2, 0, 0.02]])
    _write_log(tmp_path / "a.clf.bz2", [10.0, 9.5, 10.2], poses)  # second line out of order
    recs = read_carmen(tmp_path / "a.clf.bz2")
    assert [r.stamp for r in recs] == [10.0, 9.5, 10.2]
    assert [r.stamp for r in read_carmen(tmp_path / "a.clf.bz2", sort=True)] == [9.5, 10.0, 10.2]
    np.testing.assert_allclose(recs[1].odom, poses[1])
    scan = to_scan(recs[0])
    assert scan.ranges.shape == (180,)
    assert scan.angle_min == pytest.approx(-math.pi / 2)
    assert scan.angle_increment == pytest.approx(math.radians(1.0))


def test_reader_names_the_bad_line(tmp_path: Path) -> None:
    p = tmp_path / "bad.clf"
    p.write_text("FLASER 180 1.0 2.0\n")
    with pytest.raises(CarmenError, match=r"bad.clf:1"):
        read_carmen(p)


def test_relations_score_zero_for_truth_and_the_offset_for_a_bent_trajectory(tmp_path: Path) -> None:
    rng = np.random.default_rng(0)
    truth = np.cumsum(rng.normal(0, 0.2, (50, 3)), axis=0)
    stamps = np.arange(50) * 0.2 + 100.0
    pairs = [(i, i + 3) for i in range(0, 45, 2)]
    lines = []
    for i, j in pairs:
        d = relative(truth[i], truth[j])
        lines.append(f"{stamps[i]:.6f} {stamps[j]:.6f} {d[0]} {d[1]} 0 0 0 {d[2]}")
    (tmp_path / "r.relations").write_text("\n".join(lines))
    rel = read_relations(tmp_path / "r.relations")
    assert score_relations(rel, stamps, truth).trans_mean == pytest.approx(0.0, abs=1e-9)
    bent = truth.copy()
    bent[25:] = [compose([0.5, 0.0, 0.0], p) for p in truth[25:]]  # a 0.5 m jump between nodes 24 and 25
    s = score_relations(rel, stamps, bent)
    spanning = sum(1 for i, j in pairs if i < 25 <= j)
    assert s.n == len(pairs)
    assert s.missing == 0
    assert s.trans_mean == pytest.approx(0.5 * spanning / len(pairs), rel=0.05)


def test_scan_poses_carry_odometry_from_the_nearest_node() -> None:
    odom = np.array([[0.0, 0, 0], [0.1, 0, 0], [0.2, 0, 0], [0.3, 0, 0]])
    stamps = np.array([0.0, 0.1, 0.2, 0.3])
    nodes = np.array([[1.0, 1.0, math.pi / 2], [1.0, 1.3, math.pi / 2]])  # nodes at scans 0 and 3, rotated
    poses = scan_poses(stamps[[0, 3]], nodes, stamps, odom)
    np.testing.assert_allclose(poses[1], [1.0, 1.1, math.pi / 2], atol=1e-12)  # nearest: node 0
    np.testing.assert_allclose(poses[2], [1.0, 1.2, math.pi / 2], atol=1e-12)  # nearest: node 3
