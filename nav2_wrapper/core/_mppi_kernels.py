"""numba kernel for the MPPI controller: limit the sampled controls and roll them out in one pass.

Acceleration limits are sequential by nature (each step is limited relative to the one before), which is
56 tiny vector operations in numpy but one tight loop here; the rollout rides along in the same loop.
Compiled with cache=True like the planner's kernels, so only the first process on a machine pays.
"""

from __future__ import annotations

import math

from numba import njit


@njit(cache=True)
def limit_and_rollout(u, v0, pose, lim, acc, dt, traj):  # pragma: no cover - compiled
    """In place: clip ``u`` (K, T, 3) to ±lim and to ±acc·dt per step from ``v0`` (the measured body
    velocity), then write the omni-model poses into ``traj`` (K, T, 3)."""
    k_n, t_n = u.shape[0], u.shape[1]
    for k in range(k_n):
        px, py, th = pose[0], pose[1], pose[2]
        p0, p1, p2 = v0[0], v0[1], v0[2]
        for t in range(t_n):
            a = min(max(u[k, t, 0], -lim[0], p0 - acc[0]), lim[0], p0 + acc[0])
            b = min(max(u[k, t, 1], -lim[1], p1 - acc[1]), lim[1], p1 + acc[1])
            w = min(max(u[k, t, 2], -lim[2], p2 - acc[2]), lim[2], p2 + acc[2])
            u[k, t, 0], u[k, t, 1], u[k, t, 2] = a, b, w
            c, s = math.cos(th), math.sin(th)
            px += (c * a - s * b) * dt
            py += (s * a + c * b) * dt
            th += w * dt
            traj[k, t, 0], traj[k, t, 1], traj[k, t, 2] = px, py, th
            p0, p1, p2 = a, b, w
