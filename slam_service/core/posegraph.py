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
        """Remove node ``m`` and keep what its edges said about the others (approximate marginalisation).

        Why: all-day operation revisits the same rooms; without removing nodes the graph (and every per-node
        array) grows with the distance driven. Each edge (m, o) is re-expressed as "o seen from m"; one
        neighbour, the hub (the next node in the chain if m has one, else its strongest neighbour), keeps
        the information: every other neighbour o gets an edge hub -> o composed through m, its covariance
        the sum of both (first-order propagation). A leaf (one neighbour) just goes: it constrains nothing
        else. Cross-correlations between the new edges are dropped, as in slam_toolbox's vertex removal.
        Node 0 anchors the gauge and cannot be removed. Returns the new edges (renumbered indices).
        """
        n = self.n_nodes
        if not 0 < m < n:
            raise ValueError(f"cannot remove node {m} (have {n}; node 0 anchors the map)")
        views: dict[int, list[tuple[NDArray, NDArray, int]]] = {}  # neighbour -> [(z m->o, cov in m, kind)]
        keep = []
        for e, (i, j) in enumerate(self.edge_ij):
            if m not in (i, j):
                keep.append(e)
                continue
            z, cov = self.edge_z[e], _inv_sym(self.edge_info[e])
            if i == m:
                views.setdefault(j, []).append((z, cov, self.edge_kind[e]))
            else:
                zi, ci = _invert(z, cov)
                views.setdefault(i, []).append((zi, ci, self.edge_kind[e]))
        added: list[tuple[int, int, NDArray, NDArray, int]] = []
        if len(views) > 1:
            hub = m + 1 if m + 1 in views else max(views, key=lambda o: max(np.trace(_inv_sym(c)) for _, c, _ in
                                                                              views[o]))
            z_hub, c_hub, k_hub = _fuse(views[hub])
            z_hm, c_hm = _invert(z_hub, c_hub)  # m seen from the hub
            for o, vs in views.items():
                if o == hub:
                    continue
                z_mo, c_mo, k_mo = _fuse(vs)
                z, cov = _compose_cov(z_hm, c_hm, z_mo, c_mo)
                kind = EDGE_LOOP if EDGE_LOOP in (k_hub, k_mo) else max(k_hub, k_mo)
                added.append((hub, o, z, cov, kind))
        self.edge_ij = [self.edge_ij[e] for e in keep]
        self.edge_z = [self.edge_z[e] for e in keep]
        self.edge_info = [self.edge_info[e] for e in keep]
        self.edge_kind = [self.edge_kind[e] for e in keep]
        self.poses = np.delete(self.poses, m, axis=0)

        def shift(a: int) -> int:
            return a - 1 if a > m else a

        self.edge_ij = [(shift(i), shift(j)) for i, j in self.edge_ij]
        out = []
        for a, b, z, cov, kind in added:
            a, b = shift(a), shift(b)
            self.add_edge(a, b, z, _inv_sym(cov), kind)
            out.append((a, b))
        return out

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


def _fuse(views: list[tuple[NDArray, NDArray, int]]) -> tuple[NDArray, NDArray, int]:
    """Several measurements of the same relative pose (a sequential and a loop edge between the same
    two nodes): information-weighted mean, summed information; the strongest kind wins (loop > seq)."""
    if len(views) == 1:
        return views[0]
    infos = [_inv_sym(c) for _, c, _ in views]
    ref = views[0][0]
    # average the angle as offsets from the first one, so +pi/-pi do not cancel
    zs = [np.array([z[0], z[1], ref[2] + math.remainder(z[2] - ref[2], 2 * math.pi)]) for z, _, _ in views]
    total = sum(infos)
    z = np.linalg.solve(total, sum(i @ v for i, v in zip(infos, zs, strict=True)))
    z[2] = math.remainder(z[2], 2 * math.pi)
    return z, _inv_sym(total), max(k for _, _, k in views)
