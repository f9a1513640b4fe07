"""Log-odds occupancy grid that grows in chunks as the robot explores.

Rays are traced by sampling at half-cell steps (a numba loop, ``_raycast``, or its numpy twin until
numba is loaded); each cell gets
at most one "miss" per scan and hit cells never get a miss from the same scan, so a wall grazed by
neighbouring beams is not erased by them.

Log-odds are stored as plain (unclamped) sums, like slam_toolbox's hit/miss counts: a scan's
contribution can then be removed exactly, so after a loop closure only the nodes that actually moved
are re-rendered (``integrate(..., weight=-1)`` at the old pose, ``+1`` at the new one). The clamp
limits apply to what the map reports, not to what is stored.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from robonix_common.grid import FREE, OCCUPIED, UNKNOWN, GridMap

from . import kernels


class LogOddsGrid:
    """Cell (r, c) covers x in [ox + c res, ox + (c+1) res), row 0 at the bottom (GridMap convention)."""

    def __init__(self, resolution: float, *, hit: float = 0.85, miss: float = -0.4, lo: float = -2.0,
                 hi: float = 3.5, occupied_threshold: float = 0.2, free_threshold: float = -0.2,
                 chunk: int = 64) -> None:
        self.resolution = float(resolution)
        self.hit, self.miss, self.lo, self.hi = hit, miss, lo, hi
        self.occ_th, self.free_th = occupied_threshold, free_threshold
        self.chunk = int(chunk)
        self.logodds = np.zeros((0, 0), dtype=np.float32)
        self.c0 = 0  # global column index of array column 0 (multiple of chunk)
        self.r0 = 0

    def clear(self) -> None:
        self.logodds = np.zeros((0, 0), dtype=np.float32)
        self.c0 = self.r0 = 0

    @property
    def origin(self) -> tuple[float, float]:
        return self.c0 * self.resolution, self.r0 * self.resolution

    def _ensure(self, cmin: int, rmin: int, cmax: int, rmax: int) -> None:
        """Grow (never shrink) so global cells [cmin..cmax] x [rmin..rmax] exist; chunk-aligned."""
        k = self.chunk
        h, w = self.logodds.shape
        if w and h and cmin >= self.c0 and rmin >= self.r0 and cmax < self.c0 + w and rmax < self.r0 + h:
            return
        if w == 0 or h == 0:
            nc0, nr0 = (cmin // k) * k, (rmin // k) * k
            nc1, nr1 = (cmax // k + 1) * k, (rmax // k + 1) * k
        else:
            nc0, nr0 = min(self.c0, (cmin // k) * k), min(self.r0, (rmin // k) * k)
            nc1 = max(self.c0 + w, (cmax // k + 1) * k)
            nr1 = max(self.r0 + h, (rmax // k + 1) * k)
        new = np.zeros((nr1 - nr0, nc1 - nc0), dtype=np.float32)
        if w and h:
            new[self.r0 - nr0:self.r0 - nr0 + h, self.c0 - nc0:self.c0 - nc0 + w] = self.logodds
        self.logodds, self.c0, self.r0 = new, nc0, nr0

    def integrate(self, origin: NDArray, endpoints: NDArray, weight: float = 1.0) -> None:
        """One scan: ``origin`` (2,) sensor position, ``endpoints`` (P, 2) hits, both in the map frame.

        ``weight=-1`` removes a scan integrated earlier with the same arguments.
        """
        pts = np.ascontiguousarray(np.asarray(endpoints, dtype=np.float64).reshape(-1, 2))
        o = np.asarray(origin, dtype=np.float64)
        if len(pts) == 0:
            return
        res = self.resolution
        hc = np.floor(pts[:, 0] / res).astype(np.int64)
        hr = np.floor(pts[:, 1] / res).astype(np.int64)
        oc, orow = int(math.floor(o[0] / res)), int(math.floor(o[1] / res))
        cmin = min(int(hc.min()), oc)
        cmax = max(int(hc.max()), oc)
        rmin = min(int(hr.min()), orow)
        rmax = max(int(hr.max()), orow)
        self._ensure(cmin, rmin, cmax, rmax)
        miss, hit = np.float32(self.miss * weight), np.float32(self.hit * weight)
        if kernels.ready():
            from ._raycast import add_scan

            add_scan(self.logodds, self.r0, self.c0, float(o[0]), float(o[1]), pts, res, miss, hit, rmin, cmin,
                     rmax - rmin + 1, cmax - cmin + 1)
            return
        # numpy twin of the kernel (same cells, same float32 sums) until numba is loaded
        vec = pts - o
        length = np.hypot(vec[:, 0], vec[:, 1])
        step = 0.5 * res
        ns = np.maximum(np.floor(np.maximum(length - res, 0.0) / step).astype(np.int64), 0)  # stop before hit
        total = int(ns.sum())
        beam = np.repeat(np.arange(len(pts)), ns)
        first = np.cumsum(ns) - ns
        t = (np.arange(total) - np.repeat(first, ns)) * step
        unit = vec / np.maximum(length, 1e-9)[:, None]
        fc = np.floor((o[0] + unit[beam, 0] * t) / res).astype(np.int64)
        fr = np.floor((o[1] + unit[beam, 1] * t) / res).astype(np.int64)
        bw, bh = cmax - cmin + 1, rmax - rmin + 1
        free = np.zeros(bw * bh, dtype=bool)
        free[(fr - rmin) * bw + (fc - cmin)] = True
        hits = np.zeros(bw * bh, dtype=bool)
        hits[(hr - rmin) * bw + (hc - cmin)] = True
        free &= ~hits
        sub = self.logodds[rmin - self.r0:rmax - self.r0 + 1, cmin - self.c0:cmax - self.c0 + 1]
        upd = np.zeros(bw * bh, dtype=np.float32)
        upd[free] = miss
        upd[hits] = hit
        sub += upd.reshape(bh, bw)

    def integrate_free(self, origin: NDArray, ends: NDArray, hits: NDArray, weight: float = 1.0) -> None:
        """Clear along no-return beams: one miss on each cell from ``origin`` to ``ends`` (the beam capped at
        a clearing range), never a hit, and no miss on a cell the same scan's ``hits`` occupy. A boolean mask
        over the beams' bounding box marks each cell once (no sort: this runs for every moved node)."""
        e = np.asarray(ends, dtype=np.float64).reshape(-1, 2)
        if len(e) == 0:
            return
        o = np.asarray(origin, dtype=np.float64)
        res = self.resolution
        vec = e - o
        length = np.hypot(vec[:, 0], vec[:, 1])
        ns = np.floor(length / (0.5 * res)).astype(np.int64) + 1
        beam = np.repeat(np.arange(len(e)), ns)
        t = (np.arange(int(ns.sum())) - np.repeat(np.cumsum(ns) - ns, ns)) * (0.5 * res)
        unit = vec / np.maximum(length, 1e-9)[:, None]
        fc = np.floor((o[0] + unit[beam, 0] * t) / res).astype(np.int64)
        fr = np.floor((o[1] + unit[beam, 1] * t) / res).astype(np.int64)
        cmin, cmax, rmin, rmax = int(fc.min()), int(fc.max()), int(fr.min()), int(fr.max())
        self._ensure(cmin, rmin, cmax, rmax)
        bw, bh = cmax - cmin + 1, rmax - rmin + 1
        free = np.zeros(bw * bh, dtype=bool)
        free[(fr - rmin) * bw + (fc - cmin)] = True
        h = np.asarray(hits, dtype=np.float64).reshape(-1, 2)
        if len(h):
            hc = np.floor(h[:, 0] / res).astype(np.int64) - cmin
            hr = np.floor(h[:, 1] / res).astype(np.int64) - rmin
            inside = (hc >= 0) & (hc < bw) & (hr >= 0) & (hr < bh)
            free[hr[inside] * bw + hc[inside]] = False
        sub = self.logodds[rmin - self.r0:rmax - self.r0 + 1, cmin - self.c0:cmax - self.c0 + 1]
        sub += (free.astype(np.float32) * np.float32(self.miss * weight)).reshape(bh, bw)

    def to_gridmap(self, frame_id: str = "map") -> GridMap:
        """Trinary export: -1 unknown, 0 free, 100 occupied (thresholds on log-odds)."""
        lo = self.logodds
        data = np.full(lo.shape if lo.size else (1, 1), UNKNOWN, dtype=np.int8)
        if lo.size:
            lo = np.clip(lo, self.lo, self.hi)
            data[lo < self.free_th] = FREE
            data[lo > self.occ_th] = OCCUPIED
        ox, oy = self.origin
        return GridMap(data, self.resolution, ox, oy, 0.0, frame_id)

    def occupied_points(self) -> NDArray[np.float64]:
        """Centres of occupied cells in the map frame (for lookup grids)."""
        r, c = np.nonzero(self.logodds > self.occ_th)
        return np.stack([(c + self.c0 + 0.5) * self.resolution, (r + self.r0 + 0.5) * self.resolution], axis=1)
