"""Scan preprocessing: drop invalid beams (counted), convert to base-frame points.

Bad beams are normal on real lidars (NaN on glass, inf on no return); they must never reach the
matcher or the grid, and the provider must be able to report how many were dropped. Any planar scanner
works: the angle range and step come from the scan (180°, 270°, 360°; 0.25°-1° steps), the usable range
is the smaller of the scan's ``range_max`` and the config's ``max_range``, and the lidar's mount offset
(from TF in the provider) places the points in the robot base frame.

A reading at or beyond the scan's ``range_max`` is the driver's "no return" sentinel (many drivers report
range_max, some +inf): it is not an obstacle, never a hit. It may clear free space, up to a cap and never
past its neighbours: a no-return beam between beams that hit a wall 2 m away is a dropout (dark or specular
spot, a simulated dropout) and says nothing about the wall itself (clearing through it measured IoU
0.95 -> 0.42 on the hard sim loop); one among far or no-return neighbours is open space.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from robonix_common.scan import Scan


class ScanError(ValueError):
    """A scan is structurally unusable (bad angles/limits); the message says which field."""


@dataclass
class PreparedScan:
    points: NDArray[np.float32]  # (P, 2) beam endpoints in the robot base frame
    origin: NDArray[np.float64]  # (2,) lidar position in the base frame
    n_nan: int
    n_inf: int
    n_out_of_range: int
    n_no_return: int = 0  # readings >= range_max or +inf: no obstacle within range
    _clear: tuple | None = None  # what free_ends needs (kept so gated scans never pay for it)

    def free_ends(self, clear_range: float) -> NDArray[np.float32]:
        """(F, 2) base-frame ends of the free stretch of each no-return beam, at most ``clear_range`` m."""
        if self._clear is None or clear_range <= 0:
            return np.zeros((0, 2), dtype=np.float32)
        return _free_ends(*self._clear, clear_range)


NEIGHBOURS = 2  # beams on each side that bound a no-return beam's clearing
CLEAR_MARGIN = 0.1  # m short of the nearest neighbour's return


def prepare_scan(scan: Scan, max_range: float) -> PreparedScan:
    """Valid beams -> base-frame endpoints (no-return beams' free stretches on demand:
    :meth:`PreparedScan.free_ends`). Raises ScanError only for malformed metadata."""
    for name in ("angle_min", "angle_increment", "range_min", "range_max"):
        v = getattr(scan, name)
        if not isinstance(v, int | float | np.floating) or not math.isfinite(v):
            raise ScanError(f"Scan.{name} must be a finite number, got {v!r}")
    if scan.range_max <= scan.range_min or scan.range_min < 0:
        raise ScanError(f"Scan.range_min/range_max invalid: {scan.range_min}, {scan.range_max}")
    if scan.angle_increment == 0:
        raise ScanError("Scan.angle_increment must not be 0")
    mount = np.asarray(scan.mount, dtype=np.float64).reshape(-1)
    if mount.shape != (3,) or not np.all(np.isfinite(mount)):
        raise ScanError(f"Scan.mount must be 3 finite numbers (x, y, yaw), got {scan.mount!r}")
    r = np.asarray(scan.ranges, dtype=np.float32)
    nan = np.isnan(r)
    inf = np.isinf(r)
    finite = ~(nan | inf)
    sentinel = finite & (r >= np.float32(scan.range_max))  # the driver's "nothing within range"
    no_return = sentinel | (inf & (r > 0))
    hi = min(float(scan.range_max), float(max_range))
    ok = finite & ~sentinel & (r >= scan.range_min) & (r <= hi)
    out = int(np.count_nonzero(finite & ~ok & ~sentinel))
    idx = np.arange(r.size)
    ang = scan.angle_min + scan.angle_increment * idx[ok] + mount[2]
    rr = r[ok].astype(np.float64)
    pts = np.stack([mount[0] + rr * np.cos(ang), mount[1] + rr * np.sin(ang)], axis=1).astype(np.float32)
    n_none = int(np.count_nonzero(no_return))
    return PreparedScan(pts, mount[:2].copy(), int(nan.sum()), int(inf.sum()), out, n_none,
                        (scan, r, no_return, ok, mount) if n_none else None)


def _free_ends(scan: Scan, r: NDArray, no_return: NDArray, ok: NDArray, mount: NDArray,
               clear_range: float) -> NDArray[np.float32]:
    near = np.where(ok, r, np.inf).astype(np.float64)  # what each beam says is free (inf: as far as it knows)
    padded = np.pad(near, NEIGHBOURS, constant_values=np.inf)
    bound = np.min([padded[NEIGHBOURS + d:NEIGHBOURS + d + r.size] for d in range(-NEIGHBOURS, NEIGHBOURS + 1)
                    if d != 0], axis=0)
    reach = np.minimum(clear_range, bound - CLEAR_MARGIN)[no_return]
    sel = reach > 0
    ang = scan.angle_min + scan.angle_increment * np.flatnonzero(no_return)[sel] + mount[2]
    reach = reach[sel]
    return np.stack([mount[0] + reach * np.cos(ang), mount[1] + reach * np.sin(ang)], axis=1).astype(np.float32)
