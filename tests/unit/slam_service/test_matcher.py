"""Correlative matcher: recovers known offsets; the coarse level never prunes the true optimum."""

from __future__ import annotations

import numpy as np
import pytest

from robonix_common.geometry import transform_points
from robonix_eval.synthetic import apartment_world, drive
from slam_service.core import LookupGrid, match_scan, prepare_scan
from slam_service.core.matcher import required_margin


@pytest.fixture(scope="module")
def scene() -> tuple:
    world = apartment_world()
    rec = drive(world, range_noise=0.01, seed=3)
    g = world.ground_truth_grid()
    pad = 40
    lookup = LookupGrid.from_mask(np.pad(g.data == 100, pad), g.resolution, g.origin_x - pad * g.resolution,
                                  g.origin_y - pad * g.resolution, 0.075)
    return world, rec, lookup


@pytest.mark.parametrize(("k", "offset"), [(0, (0.2, -0.15, 0.1)), (120, (-0.25, 0.1, -0.15)), (300, (0.05, 0.22, 0.0)),
                                      (450, (0.0, 0.0, 0.18))])
def test_recovers_known_offset_on_map(scene: tuple, k: int, offset: tuple) -> None:
    _, rec, lookup = scene
    pts = prepare_scan(rec.scans[k], 12.0).points
    seed = rec.gt[k] + np.asarray(offset)
    m = match_scan(lookup, pts, seed, window_xy=0.3, window_theta=0.2, angular_step=0.008, coarse_factor=4)
    err = m.pose - rec.gt[k]
    assert np.hypot(err[0], err[1]) < 0.03  # the GT raster puts walls up to half a cell off
    assert abs(np.remainder(err[2] + np.pi, 2 * np.pi) - np.pi) < 0.01
    assert m.response > 0.5
    assert m.covariance.shape == (3, 3)
    assert np.all(np.linalg.eigvalsh(m.covariance) > 0)


def test_scan_to_scan_is_subcentimetre(scene: tuple) -> None:
    _, rec, _ = scene
    errs = []
    for k in range(0, 480, 40):
        ref = transform_points(rec.gt[k], prepare_scan(rec.scans[k], 12.0).points)
        lk = LookupGrid.from_points(ref, 0.05, 0.075, required_margin(0.3, 4, 0.075, 0.05))
        m = match_scan(lk, prepare_scan(rec.scans[k + 4], 12.0).points, rec.gt[k + 4] + [0.12, -0.08, 0.05],
                       window_xy=0.3, window_theta=0.2, angular_step=0.008, coarse_factor=4)
        errs.append(np.hypot(*(m.pose[:2] - rec.gt[k + 4][:2])))
    assert np.sqrt(np.mean(np.square(errs))) < 0.01


def test_branch_and_bound_matches_exhaustive_search(scene: tuple) -> None:
    """Without refinement, the multi-resolution result equals brute force over the same fine grid."""
    _, rec, lookup = scene
    pts = prepare_scan(rec.scans[200], 12.0).points.astype(float)
    seed = rec.gt[200] + [0.1, -0.07, 0.04]
    m = match_scan(lookup, pts, seed, window_xy=0.2, window_theta=0.05, angular_step=0.01, coarse_factor=3,
                   refine=False, penalty=0.0)
    best = -1.0
    for dt in np.arange(-5, 6) * 0.01:
        th = seed[2] + dt
        c, s = np.cos(th), np.sin(th)
        wx = seed[0] + c * pts[:, 0] - s * pts[:, 1]
        wy = seed[1] + s * pts[:, 0] + c * pts[:, 1]
        ci = np.floor((wx - lookup.origin_x) / 0.05).astype(int)
        ri = np.floor((wy - lookup.origin_y) / 0.05).astype(int)
        for dy in range(-4, 5):
            for dx in range(-4, 5):
                best = max(best, float(lookup.data[ri + dy, ci + dx].mean()))
    assert m.response == pytest.approx(best, abs=1e-6)


def test_empty_points_do_not_crash(scene: tuple) -> None:
    _, _, lookup = scene
    m = match_scan(lookup, np.zeros((0, 2)), np.zeros(3), window_xy=0.3, window_theta=0.2, angular_step=0.01,
                   coarse_factor=4)
    assert m.response == 0.0
    assert m.n_points == 0
