"""numpy <-> message converters for the hot paths (scans, grids, poses, odometry)."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from robonix_api.dds.messages import (
    Header,
    LaserScan,
    MapMetaData,
    OccupancyGrid,
    Odometry,
    Point,
    Pose,
    PoseStamped,
    PoseWithCovariance,
    Quaternion,
    Time,
    Twist,
    TwistWithCovariance,
    Vector3,
)
from robonix_common.geometry import quat_to_yaw, yaw_to_quat
from robonix_common.grid import GridMap


def to_time(stamp: float | Time) -> Time:
    """Seconds (or a Time already) as a ROS Time."""
    return stamp if isinstance(stamp, Time) else Time.from_sec(float(stamp))


def header(stamp: float | Time, frame_id: str) -> Header:
    """A ROS Header with ``stamp`` (seconds or Time) and ``frame_id``."""
    return Header(stamp=to_time(stamp), frame_id=frame_id)


# --- scans -----------------------------------------------------------------------------------------
def scan_to_numpy(msg: LaserScan) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(angles, ranges) as float64 arrays; angle i = angle_min + i * angle_increment."""
    ranges = np.asarray(msg.ranges, dtype=np.float64)
    angles = msg.angle_min + np.arange(ranges.size, dtype=np.float64) * msg.angle_increment
    return angles, ranges


def laser_scan(ranges: ArrayLike, angle_min: float, angle_increment: float, *, range_min: float = 0.0,
               range_max: float = math.inf, stamp: float | Time = 0.0, frame_id: str = "laser",
               intensities: ArrayLike | None = None, scan_time: float = 0.0,
               time_increment: float = 0.0) -> LaserScan:
    """LaserScan from a range array; angle_max follows ROS: angle of the last beam."""
    r = np.ascontiguousarray(ranges, dtype=np.float32).reshape(-1)
    inten = np.zeros(0, np.float32) if intensities is None else np.ascontiguousarray(intensities, np.float32)
    if inten.size not in (0, r.size):
        raise ValueError(f"intensities has {inten.size} values, ranges has {r.size}")
    return LaserScan(header=header(stamp, frame_id), angle_min=float(angle_min),
                     angle_max=float(angle_min + (r.size - 1) * angle_increment),
                     angle_increment=float(angle_increment), time_increment=float(time_increment),
                     scan_time=float(scan_time), range_min=float(range_min), range_max=float(range_max),
                     ranges=r, intensities=inten.reshape(-1))


# --- grids -----------------------------------------------------------------------------------------
def grid_to_msg(grid: GridMap, stamp: float | Time = 0.0, frame_id: str | None = None) -> OccupancyGrid:
    """GridMap -> OccupancyGrid (row-major, row 0 at origin: both follow ROS, so no copy of the layout)."""
    t = to_time(stamp)
    info = MapMetaData(map_load_time=t, resolution=float(grid.resolution), width=grid.width, height=grid.height,
                       origin=xyyaw_to_pose(grid.origin_x, grid.origin_y, grid.origin_yaw))
    return OccupancyGrid(header=Header(stamp=t, frame_id=frame_id or grid.frame_id), info=info,
                         data=np.ascontiguousarray(grid.data, dtype=np.int8).reshape(-1))


def msg_to_grid(msg: OccupancyGrid) -> GridMap:
    """OccupancyGrid -> GridMap; ValueError when data length != width * height."""
    w, h = int(msg.info.width), int(msg.info.height)
    data = np.asarray(msg.data, dtype=np.int8)
    if data.size != w * h:
        raise ValueError(f"OccupancyGrid.data has {data.size} cells, info says {w}x{h}={w * h}")
    x, y, yaw = pose_to_xyyaw(msg.info.origin)
    return GridMap(data.reshape(h, w), float(msg.info.resolution), x, y, yaw, msg.header.frame_id or "map")


# --- poses -----------------------------------------------------------------------------------------
def xyyaw_to_pose(x: float, y: float, yaw: float) -> Pose:
    """A planar pose as a ROS Pose (z = 0, rotation about z only)."""
    return Pose(position=Point(float(x), float(y), 0.0), orientation=Quaternion(*yaw_to_quat(float(yaw))))


def pose_to_xyyaw(p: Pose) -> tuple[float, float, float]:
    """A ROS Pose projected to the plane: x, y and the yaw of its orientation."""
    o = p.orientation
    return p.position.x, p.position.y, quat_to_yaw(o.x, o.y, o.z, o.w)


def pose_stamped(x: float, y: float, yaw: float, stamp: float | Time = 0.0, frame_id: str = "map") -> PoseStamped:
    """A planar pose as a ROS PoseStamped in ``frame_id``."""
    return PoseStamped(header=header(stamp, frame_id), pose=xyyaw_to_pose(x, y, yaw))


def twist(vx: float = 0.0, vy: float = 0.0, wz: float = 0.0) -> Twist:
    """A planar velocity (vx, vy, wz) as a ROS Twist."""
    return Twist(linear=Vector3(float(vx), float(vy), 0.0), angular=Vector3(0.0, 0.0, float(wz)))


def twist_to_tuple(t: Twist) -> tuple[float, float, float]:
    """(vx, vy, wz) — the planar part of a Twist."""
    return t.linear.x, t.linear.y, t.angular.z


def odometry(x: float, y: float, yaw: float, vx: float = 0.0, vy: float = 0.0, wz: float = 0.0, *,
             stamp: float | Time = 0.0, frame_id: str = "odom", child_frame_id: str = "base_link",
             pose_covariance: ArrayLike | None = None, twist_covariance: ArrayLike | None = None) -> Odometry:
    """Planar Odometry; the twist is in the child frame, as nav_msgs/Odometry specifies."""
    pc = np.zeros(36) if pose_covariance is None else np.asarray(pose_covariance, dtype=np.float64).reshape(-1)
    tc = np.zeros(36) if twist_covariance is None else np.asarray(twist_covariance, dtype=np.float64).reshape(-1)
    return Odometry(header=header(stamp, frame_id), child_frame_id=child_frame_id,
                    pose=PoseWithCovariance(pose=xyyaw_to_pose(x, y, yaw), covariance=pc),
                    twist=TwistWithCovariance(twist=twist(vx, vy, wz), covariance=tc))


def odometry_to_numpy(msg: Odometry) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """((x, y, yaw), (vx, vy, wz)) as arrays."""
    return np.array(pose_to_xyyaw(msg.pose.pose)), np.array(twist_to_tuple(msg.twist.twist))
