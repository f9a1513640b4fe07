"""A 3-D point cloud to a planar laser scan in a height band, as ROS's pointcloud_to_laserscan does it.

For robots with only a 3-D lidar (contract ``robonix/primitive/lidar/lidar3d``, sensor_msgs/PointCloud2):
keep the points whose height lies in ``[min_height, max_height]``, bin them by bearing, and take the
nearest range per bin, so SLAM and the costmaps can use the cloud like a 2-D scan. The parameters and
their meaning are pointcloud_to_laserscan's. Pure numpy: the caller unpacks the message
(:func:`xyz_from_packed`) and has already transformed the points into the scan frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

FLOAT32 = 7  # sensor_msgs/PointField datatype
FLOAT64 = 8


@dataclass(frozen=True)
class ScanBand:
    """pointcloud_to_laserscan's parameters (defaults as in its launch file, 360 beams over a full turn)."""

    min_height: float = -0.1
    max_height: float = 0.1
    angle_min: float = -math.pi
    angle_max: float = math.pi
    angle_increment: float = math.pi / 180.0
    range_min: float = 0.05
    range_max: float = 12.0
    use_inf: bool = True  # bins with no point: +inf (else range_max + inf_epsilon)
    inf_epsilon: float = 1.0

    def beams(self) -> int:
        return int(math.ceil((self.angle_max - self.angle_min) / self.angle_increment))


class CloudLayoutError(ValueError):
    """The cloud has no float x/y/z fields we can read; str() names what is missing."""


def xyz_from_packed(data: np.ndarray | bytes, n_points: int, point_step: int,
                    fields: dict[str, tuple[int, int]], bigendian: bool = False) -> np.ndarray:
    """(N, 3) float64 x, y, z from PointCloud2's packed bytes; ``fields`` maps name -> (offset, datatype)."""
    missing = [f for f in ("x", "y", "z") if f not in fields]
    if missing:
        raise CloudLayoutError(f"point cloud has no {'/'.join(missing)} field")
    buf = np.frombuffer(bytes(data) if not isinstance(data, np.ndarray) else data.tobytes(), dtype=np.uint8)
    if n_points * point_step > buf.size:
        raise CloudLayoutError(f"point cloud data holds {buf.size} bytes, {n_points} points of {point_step} need more")
    rows = buf[:n_points * point_step].reshape(n_points, point_step)
    out = np.empty((n_points, 3), dtype=np.float64)
    for i, name in enumerate(("x", "y", "z")):
        offset, datatype = fields[name]
        if datatype not in (FLOAT32, FLOAT64):
            raise CloudLayoutError(f"point cloud field {name}: datatype {datatype}, want FLOAT32 (7) or FLOAT64 (8)")
        size = 4 if datatype == FLOAT32 else 8
        dt = np.dtype(f"{'>' if bigendian else '<'}f{size}")
        out[:, i] = np.ascontiguousarray(rows[:, offset:offset + size]).view(dt).ravel()
    return out


def planar_scan(xyz: np.ndarray, band: ScanBand) -> np.ndarray:
    """Ranges (float32, ``band.beams()`` of them, bearing ``angle_min + i * angle_increment``): per bin the
    nearest planar range of the points within the height band and [range_min, range_max]; NaN points skipped."""
    n = band.beams()
    empty = math.inf if band.use_inf else band.range_max + band.inf_epsilon
    ranges = np.full(n, empty, dtype=np.float64)
    if xyz.size:
        x, y, z = xyz[:, 0], xyz[:, 1], xyz[:, 2]
        r = np.hypot(x, y)
        ok = np.isfinite(r) & np.isfinite(z) & (z >= band.min_height) & (z <= band.max_height)
        ok &= (r >= band.range_min) & (r <= band.range_max)
        ang = np.arctan2(y[ok], x[ok])
        keep = (ang >= band.angle_min) & (ang < band.angle_max)
        idx = ((ang[keep] - band.angle_min) / band.angle_increment).astype(np.int64)
        idx = np.clip(idx, 0, n - 1)
        np.minimum.at(ranges, idx, r[ok][keep])
    return ranges.astype(np.float32)
