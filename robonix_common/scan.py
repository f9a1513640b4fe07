"""A planar laser scan as the cores take it: what ``sensor_msgs/LaserScan`` carries, plus the mount.

One class for SLAM (which matches and integrates scans) and navigation's obstacle layer (which marks and
clears with them), so both read the same fields the same way. Plain numpy.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray


@dataclass
class Scan:
    """One planar lidar sweep (beam ``i`` at ``angle_min + i * angle_increment``); ``mount`` is the lidar
    pose in the robot base frame (x, y, yaw)."""

    ranges: NDArray[np.float32]
    angle_min: float
    angle_increment: float
    range_min: float = 0.05
    range_max: float = 12.0
    stamp: float = 0.0
    mount: tuple[float, float, float] = (0.0, 0.0, 0.0)
    frame_id: str = "laser"

    def __post_init__(self) -> None:
        self.ranges = np.asarray(self.ranges, dtype=np.float32).reshape(-1)

    @property
    def angles(self) -> NDArray[np.float64]:
        return self.angle_min + self.angle_increment * np.arange(self.ranges.size, dtype=np.float64)
