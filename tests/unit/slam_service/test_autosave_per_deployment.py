"""Two deployments on one machine share a maps root and both name their mapping service ``mapping``: each
must resume its own crash copy (issue 37 item 2: deployment A resumed deployment B's office map, IoU 0.083).
Also: a restarted service continues with the map->odom last published, not the one at the last autosave."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from robonix_api.runstate import StateFile, deployment_key
from robonix_eval.synthetic import apartment_world, drive
from slam_service.continuity import MapToOdomFile
from slam_service.core import SlamConfig, SlamEngine
from slam_service.maps import Autosave, resume_engine


def _engine(seed: int, scans: int) -> SlamEngine:
    rec = drive(apartment_world(), seed=seed)
    eng = SlamEngine(SlamConfig(), "mapping")
    for scan, odom, t in list(zip(rec.scans, rec.odom, rec.stamps, strict=True))[:scans]:
        eng.process(scan, odom, float(t))
    return eng


def _occupied(eng: SlamEngine) -> set[tuple[int, int]]:
    g = eng.map()
    rows, cols = np.nonzero(g.data >= 65)
    ox, oy = round(g.origin_x / g.resolution), round(g.origin_y / g.resolution)
    return set(zip((cols + ox).tolist(), (rows + oy).tolist(), strict=True))


def _iou(a: SlamEngine, b: SlamEngine) -> float:
    ca, cb = _occupied(a), _occupied(b)
    return len(ca & cb) / max(1, len(ca | cb))


def test_two_deployments_each_resume_their_own_map(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    maps_root = tmp_path / "maps"  # shared by both deployments
    engines = {"sim-127.0.0.1_50051": _engine(3, 60), "office-127.0.0.1_50052": _engine(11, 25)}
    assert _iou(*engines.values()) < 0.9  # two different maps
    for dep, eng in engines.items():  # both running: each autosaves
        monkeypatch.setenv("RBNX_RUN_DIR", str(tmp_path / "run" / dep))
        Autosave(maps_root, "mapping", deployment_key()).write(eng.session())
    for dep, eng in engines.items():  # a SIGKILL in each: the restart resumes from its own copy
        monkeypatch.setenv("RBNX_RUN_DIR", str(tmp_path / "run" / dep))
        session = Autosave(maps_root, "mapping", deployment_key()).read()
        assert session is not None
        resumed, _ = resume_engine(session, SlamConfig())
        assert _iou(resumed, eng) >= 0.95


def test_restart_uses_the_map_to_odom_last_published(tmp_path: Path) -> None:
    f = MapToOdomFile(StateFile(tmp_path / "mapping-map_to_odom.json"))
    assert f.last() is None
    f.note((1.0, -2.0, 0.3), 41.0)
    f.note((9.0, 9.0, 0.0), 41.1)  # within the write period: not written (throttled)
    assert MapToOdomFile(StateFile(f.file.path)).last() == (1.0, -2.0, 0.3)
    f.file.path.write_text('{"map_to_odom": [NaN, 0, 0]}')
    assert f.last() is None  # never a non-finite frame
    f.discard()
    assert not f.file.path.exists()
