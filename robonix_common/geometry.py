"""Planar (SE(2)) pose helpers shared by the cores. Numpy only: no I/O, no middleware.

A pose is ``(x, y, theta)``; composition follows the usual frame convention: ``compose(a, b)`` is
pose ``b`` (expressed in frame ``a``) expressed in ``a``'s parent frame.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

# The two spellings of a planar pose ``(x, y, theta)`` in this project, one name each:
Pose2D = tuple[float, float, float]
"""A single pose as plain floats: what services, controllers and the simulator pass around."""
PoseArray = NDArray[np.float64]
"""A pose (shape ``(3,)``) or a batch of poses (shape ``(n, 3)``) as a numpy array: what SLAM computes with."""


def wrap_angle(a: ArrayLike) -> NDArray[np.float64] | float:
    """Wrap angle(s) to [-pi, pi)."""
    w = (np.asarray(a, dtype=float) + math.pi) % (2.0 * math.pi) - math.pi
    return float(w) if np.ndim(w) == 0 else w


def yaw_to_quat(yaw: float) -> tuple[float, float, float, float]:
    """Yaw about z -> quaternion (x, y, z, w)."""
    return (0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0))


def quat_to_yaw(x: float, y: float, z: float, w: float) -> float:
    """Quaternion (x, y, z, w) -> yaw about z (roll and pitch ignored)."""
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def quat_norm(x: float, y: float, z: float, w: float) -> float:
    return math.sqrt(x * x + y * y + z * z + w * w)


def compose(a: ArrayLike, b: ArrayLike) -> NDArray[np.float64]:
    """a ⊕ b for poses (x, y, theta); b may be an (N, 3) array."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    c, s = math.cos(a[2]), math.sin(a[2])
    x = a[0] + c * b[..., 0] - s * b[..., 1]
    y = a[1] + s * b[..., 0] + c * b[..., 1]
    th = wrap_angle(a[2] + b[..., 2])
    return np.stack([x, y, np.asarray(th)], axis=-1)


def inverse(a: ArrayLike) -> NDArray[np.float64]:
    """⊖a, so that compose(a, inverse(a)) is the identity."""
    a = np.asarray(a, dtype=float)
    c, s = math.cos(a[2]), math.sin(a[2])
    return np.array([-c * a[0] - s * a[1], s * a[0] - c * a[1], -a[2]])


def relative(a: ArrayLike, b: ArrayLike) -> NDArray[np.float64]:
    """Pose of b in frame a: ⊖a ⊕ b."""
    return compose(inverse(a), b)


def transform_points(pose: ArrayLike, pts: ArrayLike) -> NDArray[np.float64]:
    """Transform (N, 2) points from the pose's frame into its parent frame."""
    pose = np.asarray(pose, dtype=float)
    pts = np.asarray(pts, dtype=float)
    c, s = math.cos(pose[2]), math.sin(pose[2])
    rot = np.array([[c, -s], [s, c]])
    return pts @ rot.T + pose[:2]
