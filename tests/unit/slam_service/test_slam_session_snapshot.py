"""Regression for a race the acceptance run hit under load: ``save_map`` takes ``engine.session()`` under
the loop lock but writes it after releasing it; the snapshot shared the live pose graph, so a scan
integrated in between made the save fail ("could not broadcast input array from shape (72,) into (73,)")."""

from __future__ import annotations

from pathlib import Path

from robonix_eval.synthetic import apartment_world, drive
from slam_service.core import SlamEngine
from slam_service.session_io import load_session, save_session


def test_session_snapshot_survives_later_scans(tmp_path: Path) -> None:
    rec = drive(apartment_world(), seed=3)
    eng = SlamEngine()
    n = len(rec.scans) // 3
    for scan, odom in zip(rec.scans[:n], rec.odom[:n], strict=True):
        eng.process(scan, odom)
    snap = eng.session()
    nodes = snap.graph.n_nodes
    assert nodes > 2
    assert len(snap.points) == nodes
    for scan, odom in zip(rec.scans[n:2 * n], rec.odom[n:2 * n], strict=True):   # the worker goes on
        eng.process(scan, odom)
    assert eng.graph.n_nodes > nodes
    assert snap.graph.n_nodes == nodes
    loaded = load_session(save_session(snap, tmp_path / "session.npz"))
    assert loaded.graph.n_nodes == nodes
    assert len(loaded.points) == nodes
