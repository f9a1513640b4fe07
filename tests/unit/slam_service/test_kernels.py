"""The numba kernels and the numpy code they replace give bit-identical results, so the provider can use
numpy until numba is loaded (off its boot) without any output depending on when that happened."""

from __future__ import annotations

import numpy as np
import pytest

from slam_service.core import kernels
from slam_service.core.lookup import LookupGrid
from slam_service.core.matcher import match_scan
from slam_service.core.occupancy import LogOddsGrid


@pytest.fixture(scope="module", autouse=True)
def _loaded() -> None:
    kernels.load()


def _scan(rng: np.random.Generator, n: int = 360) -> np.ndarray:
    ang = np.linspace(-np.pi, np.pi, n, endpoint=False)
    r = 2.0 + np.abs(np.sin(3 * ang)) * 4.0 + rng.normal(0, 0.02, n)
    return np.stack([r * np.cos(ang), r * np.sin(ang)], axis=1)


def _both(monkeypatch: pytest.MonkeyPatch, fn):  # type: ignore[no-untyped-def]
    with monkeypatch.context() as m:
        m.setattr(kernels, "ready", lambda: False)
        slow = fn()
    return slow, fn()


def test_kernels_load_and_report_ready() -> None:
    assert kernels.ready()
    assert kernels.load_in_background().name == "slam-kernels"


def test_ray_tracing_matches_numpy(monkeypatch: pytest.MonkeyPatch) -> None:
    def build() -> LogOddsGrid:
        rng = np.random.default_rng(3)
        g = LogOddsGrid(0.05)
        for k in range(12):
            o = rng.normal(0, 1.0, 2)
            pts = _scan(rng) + o
            g.integrate(o, pts, weight=1.0 if k % 4 else -1.0)  # removals too (re-rendering)
        return g

    a, b = _both(monkeypatch, build)
    assert (a.r0, a.c0, a.logodds.shape) == (b.r0, b.c0, b.logodds.shape)
    assert np.count_nonzero(a.logodds) > 1000
    np.testing.assert_array_equal(a.logodds, b.logodds)


def test_lookup_field_matches_distance_transform(monkeypatch: pytest.MonkeyPatch) -> None:
    pts = _scan(np.random.default_rng(4))
    a, b = _both(monkeypatch, lambda: LookupGrid.from_points(pts, 0.05, 0.075, 0.9))
    assert a.data.dtype == b.data.dtype == np.float32
    assert np.count_nonzero(a.data) > 1000
    np.testing.assert_array_equal(a.data, b.data)


def test_correlative_match_matches_numpy(monkeypatch: pytest.MonkeyPatch) -> None:
    rng = np.random.default_rng(5)
    pts = _scan(rng)
    lookup = LookupGrid.from_points(pts, 0.05, 0.075, 1.0)
    seed = np.array([0.11, -0.07, 0.06])
    a, b = _both(monkeypatch, lambda: match_scan(lookup, pts, seed, window_xy=0.3, window_theta=0.2,
                                                  angular_step=0.008, coarse_factor=4))
    assert a.response > 0.5
    np.testing.assert_array_equal(a.pose, b.pose)
    assert a.response == b.response
    np.testing.assert_array_equal(a.covariance, b.covariance)
