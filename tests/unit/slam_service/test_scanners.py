"""Any planar scanner: 180°-360° fields of view, 0.25°-1° steps, 30-80 m range, the max-range sentinel as
"no return", NaN/inf beams, a mount offset; and the engine maps the apartment with them."""

from __future__ import annotations

import math

import numpy as np
import pytest

from robonix_common.geometry import compose, transform_points
from robonix_eval.synthetic import apartment_world, drive
from slam_service.core import Scan, SlamConfig, SlamEngine, ate_rmse
from slam_service.core.preprocess import prepare_scan

MOUNT = (0.22, -0.05, 0.1)  # lidar ahead of and right of the base centre, yawed


def _scan(world, pose: np.ndarray, fov_deg: float, step_deg: float, range_max: float) -> tuple[Scan, np.ndarray]:
    inc = math.radians(step_deg)
    n = round(fov_deg / step_deg) + (0 if fov_deg >= 360 else 1)
    a0 = -math.pi if fov_deg >= 360 else -math.radians(fov_deg) / 2
    angles = a0 + inc * np.arange(n)
    sensor = compose(pose, np.asarray(MOUNT))
    r = world.raycast(sensor, angles + sensor[2], range_max)
    return Scan(r.astype(np.float32), a0, inc, 0.05, range_max, 0.0, MOUNT), r


@pytest.mark.parametrize(("fov", "step", "rmax"), [(180, 1.0, 30.0), (270, 0.25, 80.0), (360, 0.5, 30.0),
                                                   (270, 0.5, 60.0), (360, 0.25, 80.0)])
def test_points_land_on_the_walls_and_the_sentinel_is_no_return(fov: float, step: float, rmax: float) -> None:
    world = apartment_world()
    pose = np.array([3.0, 2.0, 0.4])
    scan, truth = _scan(world, pose, fov, step, rmax)
    r = scan.ranges
    hit = np.isfinite(r)
    r[~hit] = rmax  # the driver reports "nothing within range" as range_max
    r[::37] = np.nan  # glass
    r[5::41] = np.inf  # another driver's no-return
    prep = prepare_scan(scan, max_range=rmax)
    assert prep.n_nan == np.count_nonzero(np.isnan(r))
    assert prep.n_no_return == np.count_nonzero((r >= rmax) | np.isposinf(r))
    usable = np.isfinite(r) & (r < rmax)
    assert len(prep.points) == np.count_nonzero(usable)
    # every point, placed by the base pose and the mount, is where the beam really hit
    sensor = compose(pose, np.asarray(MOUNT))
    ang = scan.angle_min + scan.angle_increment * np.flatnonzero(usable) + sensor[2]
    expect = sensor[:2] + truth[usable][:, None] * np.stack([np.cos(ang), np.sin(ang)], axis=1)
    got = transform_points(pose, prep.points.astype(np.float64))
    assert np.abs(got - expect).max() < 1e-3
    assert np.allclose(prep.origin, MOUNT[:2])
    reach = np.hypot(*(prep.free_ends(3.0) - np.asarray(MOUNT[:2])).T)
    assert len(reach) <= prep.n_no_return
    assert np.all(reach <= 3.0 + 1e-5)


def test_missing_intensities_and_a_zero_increment() -> None:
    scan = Scan(np.full(181, 3.0, np.float32), -math.pi / 2, math.radians(1.0), 0.05, 30.0)
    assert len(prepare_scan(scan, 30.0).points) == 181  # a Scan has no intensities at all: nothing needed
    with pytest.raises(ValueError, match="angle_increment"):
        prepare_scan(Scan(np.full(10, 3.0, np.float32), 0.0, 0.0, 0.05, 30.0), 30.0)


@pytest.mark.parametrize(("fov", "step", "rmax"), [(180, 1.0, 30.0), (270, 0.5, 60.0), (360, 1.0, 80.0)])
def test_engine_maps_the_apartment_with_any_scanner(fov: float, step: float, rmax: float) -> None:
    world = apartment_world()
    rec = drive(world, seed=5, beams=4)  # only the ground truth and odometry are used
    eng = SlamEngine(SlamConfig(max_range=min(rmax, 30.0)))
    idx = []
    for k in range(min(len(rec.gt), 400)):
        scan, _ = _scan(world, rec.gt[k], fov, step, rmax)
        r = scan.ranges
        r[~np.isfinite(r)] = rmax
        r += np.random.default_rng(k).normal(0, 0.01, r.size).astype(np.float32) * (r < rmax)
        scan.stamp = float(rec.stamps[k])
        if eng.process(scan, rec.odom[k]).integrated:
            idx.append(k)
    assert len(idx) > 50
    assert ate_rmse(eng.trajectory(), rec.gt[idx]) < 0.05


def _ring_map(clear: float, sentinel: np.ndarray):
    r = np.full(360, 2.0, np.float32)
    r[sentinel] = 30.0  # the sentinel: nothing within range
    eng = SlamEngine(SlamConfig(max_range=30.0, no_return_clear_range=clear))
    assert eng.process(Scan(r, -math.pi, math.radians(1.0), 0.05, 30.0, 0.0), [0, 0, 0]).integrated
    return eng.map()


def _cell(grid, x: float, y: float) -> int:
    c, r = (int(v) for v in grid.world_to_cell(x, y))
    h, w = grid.data.shape
    return int(grid.data[r, c]) if 0 <= r < h and 0 <= c < w else -1


def test_no_return_sector_clears_free_space_up_to_the_cap_but_never_hits() -> None:
    opening = np.arange(170, 190)  # 20° around +x (beam 180 points at angle 0)
    off, on = _ring_map(0.0, opening), _ring_map(3.0, opening)
    assert _cell(off, 2.6, 0.0) == -1  # without clearing nothing is known beyond the ring's radius
    assert _cell(on, 2.6, 0.0) == 0  # free along the no-return beams ...
    assert _cell(on, 2.0, 0.0) == 0  # ... where the ring has its opening (no hit there)
    assert _cell(on, 3.4, 0.0) == -1  # ... but not past the cap
    assert _cell(on, -2.0, 0.0) == 100  # the rest of the ring is a wall


def test_a_single_dropout_does_not_clear_the_wall_behind_it() -> None:
    grid = _ring_map(3.0, np.array([180]))  # one no-return beam among hits at 2 m
    a = math.radians(1.0)
    assert _cell(grid, 2.0 * math.cos(a), 2.0 * math.sin(a)) == 100  # its neighbour's wall hit stays
    assert _cell(grid, 1.0, 0.0) == 0  # short of the wall it may clear
    assert _cell(grid, 2.3, 0.0) == -1  # behind the wall it clears nothing
