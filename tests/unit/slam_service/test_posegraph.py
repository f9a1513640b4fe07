"""Pose graph: LM on a noisy square loop closes the loop and reduces the error; node 0 stays anchored."""

from __future__ import annotations

import numpy as np
import pytest

from robonix_common.geometry import compose, relative
from slam_service.core import PoseGraph
from slam_service.core.metrics import ate_rmse
from slam_service.core.posegraph import EDGE_LOOP, EDGE_ODOM


def _square_loop(n_side: int = 10, step: float = 0.5) -> np.ndarray:
    poses = [np.zeros(3)]
    for k in range(4 * n_side):
        turn = np.pi / 2 if (k + 1) % n_side == 0 else 0.0
        poses.append(compose(poses[-1], [step, 0.0, turn]))
    return np.asarray(poses)


def test_loop_closure_optimisation_reduces_error() -> None:
    rng = np.random.default_rng(0)
    gt = _square_loop()
    g = PoseGraph()
    g.add_node(gt[0])
    info = np.diag([400.0, 400.0, 2500.0])
    for k in range(1, len(gt)):
        z = relative(gt[k - 1], gt[k]) + rng.normal(0, [0.02, 0.02, 0.02])
        g.add_node(compose(g.poses[-1], z))  # dead reckoning initial guess
        g.add_edge(k - 1, k, z, info, EDGE_ODOM)
    before = ate_rmse(g.poses, gt)
    # the loop: the last pose coincides with the first
    g.add_edge(0, len(gt) - 1, relative(gt[0], gt[-1]), np.diag([1e4, 1e4, 1e4]), EDGE_LOOP)
    cost0 = g.cost()
    res = g.optimize(20)
    after = ate_rmse(g.poses, gt)
    assert res.final_cost < 0.01 * cost0
    assert after < 0.5 * before
    assert np.allclose(g.poses[0], gt[0])  # anchored
    loop_residual = g.residuals()[-1]
    assert np.hypot(*loop_residual[:2]) < 0.01


def test_jacobians_match_finite_differences() -> None:
    from slam_service.core.posegraph import _errors

    rng = np.random.default_rng(1)
    x = rng.normal(0, 1, (2, 3))
    i, j, z = np.array([0]), np.array([1]), rng.normal(0, 1, (1, 3))
    _, a, b = _errors(x, i, j, z, jacobians=True)
    eps = 1e-6
    for node, jac in ((0, a[0]), (1, b[0])):
        for d in range(3):
            xp = x.copy()
            xp[node, d] += eps
            xm = x.copy()
            xm[node, d] -= eps
            num = (_errors(xp, i, j, z)[0][0] - _errors(xm, i, j, z)[0][0]) / (2 * eps)
            assert np.allclose(num, jac[:, d], atol=1e-5)


def test_bad_edges_are_rejected() -> None:
    g = PoseGraph()
    g.add_node([0, 0, 0])
    g.add_node([1, 0, 0])
    with pytest.raises(ValueError, match="missing nodes"):
        g.add_edge(0, 5, [1, 0, 0], np.eye(3))
    with pytest.raises(ValueError, match="positive definite"):
        g.add_edge(0, 1, [1, 0, 0], -np.eye(3))
