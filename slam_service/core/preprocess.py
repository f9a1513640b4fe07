"""Scan preprocessing: drop invalid beams (counted), convert to base-frame points.

Bad beams are normal on real lidars (NaN on glass, inf on no return); they must never reach the
matcher or the grid, and the provider must be able to report how many were dropped. Any planar scanner
works: the angle range and step come from the scan (180°, 270°, 360°; 0.25°-1° steps), the usable range
is the smaller of the scan's ``range_max`` and the config's ``max_range``, and the lidar's mount offset
(from TF in the provider) places the points in the robot base frame.

A reading at or beyond the scan's ``range_max`` is the driver's "no return" sentinel (many drivers report
range_max, some +inf): it is not an obstacle. Its direction is kept (``free_dirs``) so the map may clear
free space along it up to a cap, but it never becomes a hit.
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
    free_dirs: NDArray[np.float64] | None = None  # (F,) base-frame beam angles of no-return beams


def prepare_scan(scan: Scan, max_range: float) -> PreparedScan:
    """Valid beams -> base-frame endpoints. Raises ScanError only for malformed metadata."""
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
    free = scan.angle_min + scan.angle_increment * idx[no_return] + mount[2]
    return PreparedScan(pts, mount[:2].copy(), int(nan.sum()), int(inf.sum()), out,
                        int(np.count_nonzero(no_return)), free)
