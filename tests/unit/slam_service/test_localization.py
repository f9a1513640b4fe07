"""Save the mapped apartment (map_server files), load it, localize a new drive from a known pose."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from robonix_api.mapfile import load_map_yaml, save_map_yaml
from robonix_eval.synthetic import apartment_world, drive
from slam_service.core import SlamEngine

from .conftest import DRIFT, MappingRun


def test_localization_on_saved_map_tracks_pose(mapping_with_lc: MappingRun, tmp_path: Path) -> None:
    before = mapping_with_lc.engine.map()
    save_map_yaml(before, tmp_path / "apt.yaml")
    grid = load_map_yaml(tmp_path / "apt.yaml")
    assert np.array_equal(grid.data, before.data)

    rec = drive(apartment_world(), range_noise=0.02, dropout=0.05, odom_noise=DRIFT, seed=7)
    loc = SlamEngine()
    loc.load(grid, initial_pose=rec.gt[0])
    assert loc.mode == "localization"
    errs, matched = [], []
    for scan, odom, gt in zip(rec.scans, rec.odom, rec.gt, strict=True):
        u = loc.process(scan, odom)
        assert not u.map_changed
        e = float(np.hypot(*(u.pose_map[:2] - gt[:2])))
        errs.append(e)
        if u.integrated:
            matched.append(e)
    rmse = float(np.sqrt(np.mean(np.square(errs))))
    odom_rmse = float(np.sqrt(np.mean(np.sum((rec.odom[:, :2] - rec.gt[:, :2]) ** 2, axis=1))))
    print(f"localization RMSE {rmse:.4f} m over {len(errs)} scans (odometry alone {odom_rmse:.3f} m)")
    assert rmse <= 0.05
    assert max(matched) <= 0.08
    assert odom_rmse > 0.2
    assert loc.map() is grid  # the fixed map is served unchanged
    assert loc.graph.n_nodes == 0  # and nothing was mapped


def test_switch_to_localization_uses_current_map(mapping_with_lc: MappingRun) -> None:
    run = mapping_with_lc
    eng = SlamEngine()
    eng.load(session=run.engine.session(), mode="localization", initial_pose=run.rec.gt[0])
    k = 40
    for scan, odom in zip(run.rec.scans[:k], run.rec.odom[:k], strict=True):
        eng.process(scan, odom)
    assert np.hypot(*(eng.pose()[:2] - run.rec.gt[k - 1][:2])) < 0.05
