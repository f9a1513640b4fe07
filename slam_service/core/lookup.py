"""Likelihood-field lookup grids for correlative matching.

A lookup grid holds, per cell, exp(-d^2 / 2 sigma^2) where d is the distance to the nearest obstacle
(scan hit or occupied cell). Its one-level "max-pooled" companion gives, for a block of ``f x f``
translations, an upper bound on any score inside the block: that makes coarse-to-fine search exact
(branch and bound) instead of a heuristic that can lock onto the wrong peak.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from . import kernels

if TYPE_CHECKING:
    from scipy.spatial import cKDTree


@dataclass
class LookupGrid:
    data: NDArray[np.float32]  # (H, W), row 0 at the bottom, border cells are 0
    resolution: float
    origin_x: float
    origin_y: float
    points: NDArray[np.float64] | None = None  # obstacle points (map frame) for ICP refinement
    _pooled: dict[int, NDArray[np.float32]] = field(default_factory=dict, repr=False)
    _tree: cKDTree | None = field(default=None, repr=False)

    def kdtree(self) -> cKDTree:
        """Nearest-obstacle queries at full precision (built lazily; cell centres if no points)."""
        if self._tree is None:
            if self.points is None:
                r, c = np.nonzero(self.data >= 0.999 * self.data.max()) if self.data.any() else ([], [])
                self.points = np.stack([self.origin_x + (np.asarray(c) + 0.5) * self.resolution,
                                        self.origin_y + (np.asarray(r) + 0.5) * self.resolution], axis=1)
            from scipy.spatial import cKDTree  # loaded with the first scan, not at start-up (boot time)

            self._tree = cKDTree(self.points if len(self.points) else np.zeros((1, 2)) + 1e9)
        return self._tree

    @property
    def shape(self) -> tuple[int, int]:
        return self.data.shape  # type: ignore[return-value]

    def pooled(self, f: int) -> NDArray[np.float32]:
        """U[r, c] = max(L[r:r+f, c:c+f]): the bound used by the coarse search level (cached)."""
        if f not in self._pooled:
            u = self.data
            if f > 1:
                h, w = u.shape
                pad = np.zeros((h + f - 1, w + f - 1), dtype=np.float32)
                pad[:h, :w] = u
                rows = pad[:h].copy()
                for k in range(1, f):
                    np.maximum(rows, pad[k:k + h], out=rows)
                u = rows[:, :w].copy()
                for k in range(1, f):
                    np.maximum(u, rows[:, k:k + w], out=u)
            self._pooled[f] = u
        return self._pooled[f]

    @classmethod
    def from_mask(cls, mask: NDArray[np.bool_], resolution: float, origin_x: float, origin_y: float,
                  sigma: float, sub_xy: NDArray | None = None) -> LookupGrid:
        """Obstacle mask (row 0 = bottom) -> smoothed field; the caller provides the margin.

        ``sub_xy`` (H, W, 2), optional: the obstacle's position inside each obstacle cell, in cells
        relative to the cell centre. Distances are then measured to those points rather than to cell
        centres, which keeps sub-cell accuracy (a rasterised field alone biases matches by up to
        half a cell, and that drift accumulates along the chain).
        """
        if not mask.any():
            return cls(np.zeros(mask.shape, dtype=np.float32), resolution, origin_x, origin_y)
        from scipy import ndimage  # loaded with the first scan, not at start-up (boot time)

        s = sigma / resolution
        cut2 = (3.0 * s) ** 2
        data = np.zeros(mask.shape, dtype=np.float32)
        if sub_xy is None and kernels.ready():
            from ._field import gaussian_field  # stamps the cut field instead of a full EDT (same values)

            r, c = np.nonzero(mask)
            data = gaussian_field(r.astype(np.int64), c.astype(np.int64), mask.shape[0], mask.shape[1], float(s),
                                  float(cut2))
        elif sub_xy is None:
            d2 = ndimage.distance_transform_edt(~mask) ** 2
            data[:] = np.where(d2 <= cut2, np.exp(-0.5 * d2 / (s * s)), 0.0)
        else:
            dist, idx = ndimage.distance_transform_edt(~mask, return_indices=True)
            br, bc = np.nonzero(dist <= 3.0 * s + 1.5)
            nr, nc = idx[0][br, bc], idx[1][br, bc]
            h, w = mask.shape
            best = np.full(len(br), np.inf)
            # the nearest obstacle *cell* is not always the one holding the nearest *point*: check its 3x3
            for dr in (-1, 0, 1):
                r2 = np.clip(nr + dr, 0, h - 1)
                for dc in (-1, 0, 1):
                    c2 = np.clip(nc + dc, 0, w - 1)
                    dx = c2 + sub_xy[r2, c2, 0] - bc
                    dy = r2 + sub_xy[r2, c2, 1] - br
                    np.minimum(best, np.where(mask[r2, c2], dx * dx + dy * dy, np.inf), out=best)
            data[br, bc] = np.where(best <= cut2, np.exp(-0.5 * best / (s * s)), 0.0)
        data[0, :] = data[-1, :] = 0.0
        data[:, 0] = data[:, -1] = 0.0
        return cls(data, resolution, origin_x, origin_y)

    @classmethod
    def from_points(cls, points: NDArray, resolution: float, sigma: float, margin: float,
                    center: NDArray | None = None, half_extent: float | None = None,
                    sub_cell: bool = False) -> LookupGrid:
        """Map-frame hit points -> lookup grid covering them plus ``margin`` (optionally cropped).

        ``sub_cell`` measures field distances to the per-cell mean points (slower); off by default
        because the correlative search only needs cell accuracy and the refinement uses the points.
        """
        pts = np.asarray(points, dtype=np.float64)
        if center is not None and half_extent is not None and len(pts):
            keep = np.all(np.abs(pts - center[:2]) <= half_extent, axis=1)
            pts = pts[keep]
        if len(pts) == 0:
            c = np.zeros(2) if center is None else np.asarray(center[:2], dtype=float)
            lo = c - margin
            n = max(3, int(math.ceil(2 * margin / resolution)))
            return cls(np.zeros((n, n), dtype=np.float32), resolution, float(lo[0]), float(lo[1]))
        lo = np.floor((pts.min(axis=0) - margin) / resolution) * resolution
        hi = pts.max(axis=0) + margin
        w, h = (np.ceil((hi - lo) / resolution).astype(int) + 1)
        u = (pts[:, 0] - lo[0]) / resolution
        v = (pts[:, 1] - lo[1]) / resolution
        c = np.floor(u).astype(np.int64)
        r = np.floor(v).astype(np.int64)
        flat = r * w + c
        cnt = np.bincount(flat, minlength=h * w)
        mask = (cnt > 0).reshape(h, w)
        sub = np.zeros((h * w, 2))
        nz = cnt > 0
        sub[nz, 0] = np.bincount(flat, u - c - 0.5, minlength=h * w)[nz] / cnt[nz]
        sub[nz, 1] = np.bincount(flat, v - r - 0.5, minlength=h * w)[nz] / cnt[nz]
        if not sub_cell:
            out = cls.from_mask(mask, resolution, float(lo[0]), float(lo[1]), sigma)
        else:
            out = cls.from_mask(mask, resolution, float(lo[0]), float(lo[1]), sigma, sub.reshape(h, w, 2))
        # one mean point per cell: exact enough for point-to-line refinement, and 3-4x fewer points
        r_nz, c_nz = np.divmod(np.flatnonzero(nz), w)
        out.points = np.stack([lo[0] + (c_nz + 0.5 + sub[nz, 0]) * resolution,
                               lo[1] + (r_nz + 0.5 + sub[nz, 1]) * resolution], axis=1)
        return out

    def sample_bilinear(self, x: NDArray, y: NDArray) -> tuple[NDArray, NDArray, NDArray]:
        """Field value and gradient (d/dx, d/dy) at continuous positions; zero outside."""
        u = (x - self.origin_x) / self.resolution - 0.5
        v = (y - self.origin_y) / self.resolution - 0.5
        h, w = self.data.shape
        c0 = np.clip(np.floor(u).astype(np.int64), 0, w - 2)
        r0 = np.clip(np.floor(v).astype(np.int64), 0, h - 2)
        fu = np.clip(u - c0, 0.0, 1.0)
        fv = np.clip(v - r0, 0.0, 1.0)
        d = self.data
        v00, v01 = d[r0, c0], d[r0, c0 + 1]
        v10, v11 = d[r0 + 1, c0], d[r0 + 1, c0 + 1]
        val = (1 - fv) * ((1 - fu) * v00 + fu * v01) + fv * ((1 - fu) * v10 + fu * v11)
        gx = ((1 - fv) * (v01 - v00) + fv * (v11 - v10)) / self.resolution
        gy = ((1 - fu) * (v10 - v00) + fu * (v11 - v01)) / self.resolution
        return val, gx, gy
