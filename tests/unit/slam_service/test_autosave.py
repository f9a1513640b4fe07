"""The mapping service's crash copy without processes: atomic write, read back, discard on a fresh start,
and an engine resumed from it renders the same map and the right map->odom."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from robonix_common.geometry import compose
from robonix_eval.synthetic import apartment_world, drive
from slam_service.core import SlamConfig, SlamEngine
from slam_service.maps import Autosave, MapIdError, MapStore, resume_engine


def _mapped_engine() -> SlamEngine:
    rec = drive(apartment_world(), seed=3)
    eng = SlamEngine(SlamConfig(), "mapping")
    for scan, odom, t in list(zip(rec.scans, rec.odom, rec.stamps, strict=True))[:80]:
        eng.process(scan, odom, float(t))
    assert eng.graph.n_nodes > 3
    return eng


def test_autosave_round_trip_resume_and_discard(tmp_path: Path) -> None:
    eng = _mapped_engine()
    store = Autosave(tmp_path, "mapping")
    assert store.read() is None
    store.write(eng.session())
    assert store.path == tmp_path / ".autosave" / "mapping" / "session.npz"
    assert [p.name for p in store.folder.iterdir()] == ["session.npz"]  # no temp file left
    assert MapStore(tmp_path).list() == []  # a crash copy is not a saved map

    session = store.read()
    assert session is not None
    resumed, m2o = resume_engine(session, SlamConfig())
    assert resumed.mode == "mapping"
    assert resumed.graph.n_nodes == eng.graph.n_nodes
    np.testing.assert_array_equal(resumed.map().data, eng.map().data)
    # map->odom at the last node: composing it with that node's odometry gives the node's map pose
    last = compose(m2o, session.odom[-1])
    np.testing.assert_allclose(last[:2], session.graph.poses[-1][:2], atol=1e-9)
    assert math.isclose(float(last[2]), float(session.graph.poses[-1][2]), abs_tol=1e-9)

    store.discard()
    assert store.read() is None
    store.discard()  # idempotent


def test_instance_names_that_are_not_file_names_are_refused(tmp_path: Path) -> None:
    with pytest.raises(MapIdError):
        Autosave(tmp_path, "../escape")
