"""CARMEN ``.clf`` laser logs (the Freiburg / Radish benchmark format) as plain numpy records.

Only what a 2D SLAM run needs: ``FLASER`` lines (front laser: ranges, odometry pose, IPC timestamp).
``ODOM``-only lines are ignored: every FLASER line carries the odometry pose at the scan. Real logs are
not strictly time-ordered and come in bursts; the reader keeps the file order (what a replay of the log
would deliver) and :func:`read_carmen` can sort by stamp on request.
"""

from __future__ import annotations

import bz2
import gzip
import math
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from robonix_common.scan import Scan

# CARMEN writes beams without a return as the scanner's maximum (81.83 m on SICK LMS in these logs, or
# 50 m); anything this far is no return, never a wall.
NO_RETURN_M = 50.0


class CarmenError(ValueError):
    """A malformed line; the message names the line number and what is wrong."""


@dataclass(frozen=True)
class LaserRecord:
    stamp: float  # s, ipc_timestamp (the time base of Kuemmerle et al.'s relation files)
    ranges: NDArray[np.float32]  # m, beams from -fov/2 counter-clockwise
    odom: NDArray[np.float64]  # (x, y, theta) odometry pose at the scan


def _open(path: Path):
    if path.suffix == ".bz2":
        return bz2.open(path, "rt")
    if path.suffix == ".gz":
        return gzip.open(path, "rt")
    return open(path)


def iter_flaser(path: str | Path) -> Iterator[LaserRecord]:
    """FLASER records in file order. Raises :class:`CarmenError` naming the line on malformed input."""
    p = Path(path)
    with _open(p) as fh:
        for lineno, line in enumerate(fh, 1):
            if not line.startswith("FLASER"):
                continue
            f = line.split()
            try:
                n = int(f[1])
                ranges = np.asarray(f[2:2 + n], dtype=np.float32)
                rest = f[2 + n:]
                odom = np.asarray(rest[3:6], dtype=np.float64)
                stamp = float(rest[6])
            except (IndexError, ValueError) as exc:
                raise CarmenError(f"{p.name}:{lineno}: malformed FLASER line ({exc})") from exc
            if len(ranges) != n or odom.shape != (3,):
                raise CarmenError(f"{p.name}:{lineno}: FLASER line has {len(ranges)} of {n} ranges")
            yield LaserRecord(stamp, ranges, odom)


def read_carmen(path: str | Path, max_scans: int | None = None, sort: bool = False) -> list[LaserRecord]:
    """The first ``max_scans`` FLASER records (file order), optionally sorted by stamp (stable)."""
    out: list[LaserRecord] = []
    for rec in iter_flaser(path):
        out.append(rec)
        if max_scans is not None and len(out) >= max_scans:
            break
    if sort:
        out.sort(key=lambda r: r.stamp)
    return out


def to_scan(rec: LaserRecord, fov: float = math.pi, range_max: float = NO_RETURN_M) -> Scan:
    """A :class:`Scan` for the SLAM core: 180 degree scanners with n beams spaced fov/n (CARMEN's
    -90..+89 degree convention for 180 one-degree beams)."""
    n = len(rec.ranges)
    inc = fov / n if n else 0.0
    return Scan(rec.ranges.astype(np.float32), -fov / 2, inc, range_min=0.01, range_max=range_max, stamp=rec.stamp)
