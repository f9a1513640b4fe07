"""SE(2) pose graph and a sparse Levenberg-Marquardt optimiser (in the spirit of Konolige's SPA).

Edges carry a relative-pose measurement z_ij (pose of j in frame i) and a 3x3 information matrix.
All Jacobians are computed for every edge at once and assembled into a scipy.sparse normal matrix;
node 0 is anchored (its block is removed), which fixes the gauge so the map frame stays put.

Loop edges can get a Huber kernel (iteratively reweighted): a loop measurement that disagrees with the
rest of the graph by more than ``huber`` standard deviations pulls with a bounded force instead of a
quadratic one, so one slightly wrong closure cannot bend a precise scan-matching chain. Huber (not a
redescending kernel) keeps a correct first closure after long drift effective: its pull never vanishes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    import scipy.sparse as sp

EDGE_ODOM, EDGE_SEQUENTIAL, EDGE_LOOP = 0, 1, 2


@dataclass
class OptimizeResult:
    iterations: int
    initial_cost: float
    final_cost: float
    max_change: float  # largest node translation (m)


@dataclass
class PoseGraph:
    poses: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 3)))
    edge_ij: list[tuple[int, int]] = field(default_factory=list)
    edge_z: list[NDArray[np.float64]] = field(default_factory=list)
    edge_info: list[NDArray[np.float64]] = field(default_factory=list)
    edge_kind: list[int] = field(default_factory=list)

    @property
    def n_nodes(self) -> int:
        return len(self.poses)

    @property
    def n_edges(self) -> int:
        return len(self.edge_ij)

    def add_node(self, pose: NDArray) -> int:
        self.poses = np.vstack([self.poses, np.asarray(pose, dtype=float).reshape(1, 3)])
        return self.n_nodes - 1

    def add_edge(self, i: int, j: int, z: NDArray, info: NDArray, kind: int = EDGE_SEQUENTIAL) -> None:
        if not (0 <= i < self.n_nodes and 0 <= j < self.n_nodes) or i == j:
            raise ValueError(f"edge ({i}, {j}) refers to missing nodes (have {self.n_nodes})")
        info = np.asarray(info, dtype=float).reshape(3, 3)
        if not np.all(np.isfinite(info)) or np.any(np.linalg.eigvalsh(0.5 * (info + info.T)) <= 0):
            raise ValueError(f"edge ({i}, {j}): information matrix must be symmetric positive definite")
        self.edge_ij.append((int(i), int(j)))
        self.edge_z.append(np.asarray(z, dtype=float).reshape(3).copy())
        self.edge_info.append(0.5 * (info + info.T))
        self.edge_kind.append(int(kind))

    def remove_last_edge(self) -> None:
        """Drop the most recently added edge (a loop closure that failed a post-optimisation check)."""
        for lst in (self.edge_ij, self.edge_z, self.edge_info, self.edge_kind):
            lst.pop()

    def remove_node(self, m: int) -> list[tuple[int, int]]:
        """Remove node ``m``, keeping the graph connected and its current shape (lifelong pruning).

        Why this way: re-expressing all of a removed node's edges through one neighbour (a star) makes that
        neighbour inherit them; when old nodes are pruned one after another along their chain the survivor
        collects every loop edge of the pass (degree 25+ seen) and composite edges of composites skew the
        map. Instead, every later neighbour ``u`` of ``m`` that has no other earlier neighbour (normally just
        the next node of the chain) gets an edge from ``m``'s latest earlier neighbour ``p``: its measurement
        is the *current* relative pose of the two (the optimised geometry, loop corrections included, is
        kept exactly: zero residual), its covariance the first-order composition of the two edges through
        ``m`` (the chain's stiffness). ``m``'s other edges (loop closures) go with it; their correction is
        already in the poses. Every node keeps an earlier neighbour, so the graph stays connected to node 0,
        which anchors the gauge and cannot be removed. Returns the added edges (indices after removal).
        """
        n = self.n_nodes
        if not 0 < m < n:
            raise ValueError(f"cannot remove node {m} (have {n}; node 0 anchors the map)")
        incident = [e for e, (i, j) in enumerate(self.edge_ij) if m in (i, j)]
        nbrs = {o for e in incident for o in self.edge_ij[e]} - {m}
        has_lower = {max(i, j) for i, j in self.edge_ij if m not in (i, j) and max(i, j) in nbrs}
        earlier = [o for o in nbrs if o < m]
        orphans = sorted(u for u in nbrs if u > m and u not in has_lower)
        added: list[tuple[int, int, NDArray, NDArray]] = []
        if earlier and orphans:
            p = max(earlier)
            z_pm, c_pm = self._view(incident, p, m)
            for u in orphans:
                z_mu, c_mu = self._view(incident, m, u)
                _, cov = _compose_cov(z_pm, c_pm, z_mu, c_mu)
                added.append((p, u, _relative(self.poses[p], self.poses[u]), cov))
        gone = set(incident)
        keep = [e for e in range(self.n_edges) if e not in gone]

        def shift(a: int) -> int:
            return a - 1 if a > m else a

        self.edge_ij = [(shift(self.edge_ij[e][0]), shift(self.edge_ij[e][1])) for e in keep]
        self.edge_z = [self.edge_z[e] for e in keep]
        self.edge_info = [self.edge_info[e] for e in keep]
        self.edge_kind = [self.edge_kind[e] for e in keep]
        self.poses = np.delete(self.poses, m, axis=0)
        out = []
        for a, b, z, cov in added:
            self.add_edge(shift(a), shift(b), z, _inv_sym(cov), EDGE_SEQUENTIAL)
            out.append((shift(a), shift(b)))
        return out

    def _view(self, edges: list[int], a: int, b: int) -> tuple[NDArray, NDArray]:
        """Pose of ``b`` in ``a``'s frame with its covariance, from the strongest edge among ``edges`` between
        them (in either direction)."""
        best: tuple[float, NDArray, NDArray] | None = None
        for e in edges:
            i, j = self.edge_ij[e]
            if {i, j} != {a, b}:
                continue
            cov = _inv_sym(self.edge_info[e])
            z, c = (self.edge_z[e], cov) if i == a else _invert(self.edge_z[e], cov)
            if best is None or np.trace(c) < best[0]:
                best = (float(np.trace(c)), z, c)
        assert best is not None, f"no edge between {a} and {b}"
        return best[1], best[2]

    def _arrays(self) -> tuple[NDArray, NDArray, NDArray, NDArray]:
        ij = np.asarray(self.edge_ij, dtype=np.int64).reshape(-1, 2)
        return ij[:, 0], ij[:, 1], np.asarray(self.edge_z).reshape(-1, 3), np.asarray(self.edge_info).reshape(-1, 3, 3)

    def residuals(self, poses: NDArray | None = None) -> NDArray[np.float64]:
        """e_ij = z_ij^-1 (x_i^-1 x_j) as (dx, dy, dtheta), one row per edge."""
        x = self.poses if poses is None else poses
        i, j, z, _ = self._arrays()
        return _errors(x, i, j, z)[0]

    def cost(self, poses: NDArray | None = None) -> float:
        _, _, _, info = self._arrays()
        e = self.residuals(poses)
        return float(np.einsum("ei,eij,ej->", e, info, e))

    def edge_chi2(self, poses: NDArray | None = None) -> NDArray[np.float64]:
        """Mahalanobis squared error of every edge (no kernel)."""
        _, _, _, info = self._arrays()
        e = self.residuals(poses)
        return np.einsum("ei,eij,ej->e", e, info, e)

    def optimize(self, iterations: int = 15, tol: float = 1e-6, huber: float | None = None) -> OptimizeResult:
        """Levenberg-Marquardt on all nodes but node 0; updates ``poses`` in place.

        ``huber``: kernel width (in standard deviations) applied to loop edges; None = plain least squares.
        """
        n = self.n_nodes
        if n < 2 or self.n_edges == 0:
            c = self.cost() if self.n_edges else 0.0
            return OptimizeResult(0, c, c, 0.0)
        i, j, z, info = self._arrays()
        robust = np.asarray(self.edge_kind) == EDGE_LOOP if huber else np.zeros(len(i), dtype=bool)
        k2 = float(huber or 0.0) ** 2

        def cost_and_weights(err: NDArray) -> tuple[float, NDArray]:
            chi2 = np.einsum("ei,eij,ej->e", err, info, err)
            w = np.ones(len(chi2))
            rho = chi2.copy()
            big = robust & (chi2 > k2)
            r = np.sqrt(chi2[big])
            w[big] = np.sqrt(k2) / r
            rho[big] = 2.0 * np.sqrt(k2) * r - k2
            return float(rho.sum()), w

        from scipy import sparse  # imported on first use: keeps scipy out of the provider's start-up
        from scipy.sparse import linalg as sparse_linalg

        x = self.poses.copy()
        start = x.copy()
        e, a, b = _errors(x, i, j, z, jacobians=True)
        cost0, wts = cost_and_weights(e)
        cost = cost0
        lam = 1e-4
        done_iters = 0
        for step_no in range(1, iterations + 1):
            done_iters = step_no
            h, g = _normal_equations(n, i, j, e, a, b, info * wts[:, None, None])
            h = h[3:, 3:]
            g = g[3:]
            diag = h.diagonal()
            improved = False
            for _ in range(8):
                hl = h + sparse.diags(lam * (diag + 1e-9), format="csc")
                dx = sparse_linalg.spsolve(hl, -g)
                if not np.all(np.isfinite(dx)):
                    lam *= 10
                    continue
                xn = x.copy()
                xn[1:] += dx.reshape(-1, 3)
                xn[:, 2] = np.remainder(xn[:, 2] + math.pi, 2 * math.pi) - math.pi
                en = _errors(xn, i, j, z)[0]
                cn, wn = cost_and_weights(en)
                if cn <= cost:
                    x, lam, improved, wts = xn, max(lam / 10, 1e-9), True, wn
                    done = (cost - cn) <= tol * max(cost, 1e-12) or np.abs(dx).max() < 1e-7
                    cost = cn
                    break
                lam *= 10
            if not improved:
                break
            e, a, b = _errors(x, i, j, z, jacobians=True)
            if done:
                break
        self.poses = x
        change = float(np.hypot(*(x[:, :2] - start[:, :2]).T).max())
        return OptimizeResult(done_iters, cost0, cost, change)


def _errors(x: NDArray, i: NDArray, j: NDArray, z: NDArray, jacobians: bool = False
            ) -> tuple[NDArray, NDArray | None, NDArray | None]:
    xi, xj = x[i], x[j]
    ci, si = np.cos(xi[:, 2]), np.sin(xi[:, 2])
    cz, sz = np.cos(z[:, 2]), np.sin(z[:, 2])
    dtx, dty = xj[:, 0] - xi[:, 0], xj[:, 1] - xi[:, 1]
    # d = R_i^T (t_j - t_i); e_t = R_z^T (d - t_z)
    dx = ci * dtx + si * dty
    dy = -si * dtx + ci * dty
    ux, uy = dx - z[:, 0], dy - z[:, 1]
    e = np.empty((len(i), 3))
    e[:, 0] = cz * ux + sz * uy
    e[:, 1] = -sz * ux + cz * uy
    e[:, 2] = np.remainder(xj[:, 2] - xi[:, 2] - z[:, 2] + math.pi, 2 * math.pi) - math.pi
    if not jacobians:
        return e, None, None
    # R_z^T R_i^T, and R_z^T dR_i^T/dtheta (t_j - t_i)
    rzt = np.stack([np.stack([cz, sz], -1), np.stack([-sz, cz], -1)], axis=1)  # (E, 2, 2)
    rit = np.stack([np.stack([ci, si], -1), np.stack([-si, ci], -1)], axis=1)
    m = rzt @ rit
    dth = np.stack([-si * dtx + ci * dty, -ci * dtx - si * dty], axis=-1)  # dR_i^T/dtheta (t_j - t_i)
    dth = np.einsum("eab,eb->ea", rzt, dth)
    a = np.zeros((len(i), 3, 3))
    b = np.zeros((len(i), 3, 3))
    a[:, :2, :2] = -m
    a[:, :2, 2] = dth
    a[:, 2, 2] = -1.0
    b[:, :2, :2] = m
    b[:, 2, 2] = 1.0
    return e, a, b


def _normal_equations(n: int, i: NDArray, j: NDArray, e: NDArray, a: NDArray, b: NDArray, info: NDArray
                      ) -> tuple[sp.csc_matrix, NDArray]:
    from scipy import sparse

    at_o = np.einsum("eki,ekl->eil", a, info)  # A^T Omega
    bt_o = np.einsum("eki,ekl->eil", b, info)
    blocks = [(i, i, at_o @ a), (i, j, at_o @ b), (j, i, bt_o @ a), (j, j, bt_o @ b)]
    rows, cols, vals = [], [], []
    rr, cc = np.meshgrid(np.arange(3), np.arange(3), indexing="ij")
    for bi, bj, blk in blocks:
        rows.append((3 * bi[:, None, None] + rr[None]).ravel())
        cols.append((3 * bj[:, None, None] + cc[None]).ravel())
        vals.append(blk.ravel())
    h = sparse.coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(3 * n, 3 * n)).tocsc()
    g = np.zeros(3 * n)
    np.add.at(g, (3 * i[:, None] + np.arange(3)).ravel(), np.einsum("eil,el->ei", at_o, e).ravel())
    np.add.at(g, (3 * j[:, None] + np.arange(3)).ravel(), np.einsum("eil,el->ei", bt_o, e).ravel())
    return h, g


def _inv_sym(a: NDArray) -> NDArray:
    """Inverse of a symmetric positive definite 3x3 (information <-> covariance), symmetrised."""
    b = np.linalg.inv(0.5 * (a + a.T))
    return 0.5 * (b + b.T)


def _rot(t: float) -> NDArray:
    c, s = math.cos(t), math.sin(t)
    return np.array([[c, -s], [s, c]])


def _invert(z: NDArray, cov: NDArray) -> tuple[NDArray, NDArray]:
    """z = pose of b in frame a with covariance in frame a -> pose of a in frame b, covariance in frame b."""
    r = _rot(z[2])
    t = -r.T @ z[:2]
    j = np.zeros((3, 3))
    j[:2, :2] = -r.T
    j[:2, 2] = (t[1], -t[0])  # d(-R^T t_z)/dtheta, written in the inverted translation t
    j[2, 2] = -1.0
    return np.array([t[0], t[1], -z[2]]), j @ cov @ j.T


def _compose_cov(a: NDArray, ca: NDArray, b: NDArray, cb: NDArray) -> tuple[NDArray, NDArray]:
    """a (b in frame h) o b (c in frame b): c in frame h, covariance by first-order propagation."""
    r = _rot(a[2])
    tb = r @ b[:2]
    z = np.array([a[0] + tb[0], a[1] + tb[1], math.remainder(a[2] + b[2], 2 * math.pi)])
    ja = np.eye(3)
    ja[0, 2], ja[1, 2] = -tb[1], tb[0]
    jb = np.eye(3)
    jb[:2, :2] = r
    cov = ja @ ca @ ja.T + jb @ cb @ jb.T
    return z, 0.5 * (cov + cov.T)



def _relative(a: NDArray, b: NDArray) -> NDArray:
    """Pose of b in the frame of a (kept local: the graph module depends on numpy alone)."""
    c, s = math.cos(a[2]), math.sin(a[2])
    dx, dy = b[0] - a[0], b[1] - a[1]
    return np.array([c * dx + s * dy, -s * dx + c * dy, math.remainder(b[2] - a[2], 2 * math.pi)])
