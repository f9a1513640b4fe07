"""CARMEN ``.clf`` laser log -> rosbag2 (rosbags' own writer), for users with classic datasets.

Topics: ``/scan`` (sensor_msgs/LaserScan, frame ``laser``), ``/odom`` (nav_msgs/Odometry odom ->
base_link), ``/tf`` (odom -> base_link at every scan) and ``/tf_static`` (base_link -> laser, identity:
CARMEN's FLASER ranges are already in the robot frame). Header stamps are the log's own IPC stamps,
unchanged: bursty and partly out of order, as the robot's logger wrote them. The bag's log times are the
file order made monotonic (a stamp older than the previous line is logged at the previous time), so a
replay delivers the scans in the order and with the bursts of the original log.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from robonix_eval.carmen import NO_RETURN_M, iter_flaser

FOV = math.pi  # CARMEN FLASER: 180 degrees from -90 degrees


class ConvertError(ValueError):
    """Bad input or output path; the message says which."""


def convert_carmen(src: str | Path, dst: str | Path, max_scans: int | None = None) -> int:
    """Write the FLASER lines of ``src`` (``.clf``, ``.clf.bz2``, ``.clf.gz``) as a rosbag2 directory
    ``dst`` (sqlite3, version 8). Returns the number of scans written."""
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_typestore

    src, dst = Path(src), Path(dst)
    if not src.is_file():
        raise ConvertError(f"no such log: {src}")
    if dst.exists():
        raise ConvertError(f"output exists: {dst} (rosbag2 writes a new directory)")
    ts = get_typestore(Stores.ROS2_HUMBLE)
    t = ts.types
    hdr, stamp_t = t["std_msgs/msg/Header"], t["builtin_interfaces/msg/Time"]
    vec, quat = t["geometry_msgs/msg/Vector3"], t["geometry_msgs/msg/Quaternion"]
    tf_t, tfs_t = t["geometry_msgs/msg/Transform"], t["geometry_msgs/msg/TransformStamped"]

    def header(sec: float, frame: str):
        ns = int(round(sec * 1e9))
        return hdr(stamp=stamp_t(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000), frame_id=frame)

    def tf(sec: float, parent: str, child: str, x: float, y: float, yaw: float):
        q = quat(x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2))
        return tfs_t(header=header(sec, parent), child_frame_id=child,
                     transform=tf_t(translation=vec(x=x, y=y, z=0.0), rotation=q))

    n = 0
    last_ns = 0
    with Writer(dst, version=8) as w:
        c_scan = w.add_connection("/scan", "sensor_msgs/msg/LaserScan", typestore=ts)
        c_odom = w.add_connection("/odom", "nav_msgs/msg/Odometry", typestore=ts)
        c_tf = w.add_connection("/tf", "tf2_msgs/msg/TFMessage", typestore=ts)
        c_static = w.add_connection("/tf_static", "tf2_msgs/msg/TFMessage", typestore=ts)
        for rec in iter_flaser(src):
            sec = rec.stamp
            log_ns = max(last_ns, int(round(sec * 1e9)))
            if n == 0:
                static = t["tf2_msgs/msg/TFMessage"](transforms=[tf(sec, "base_link", "laser", 0.0, 0.0, 0.0)])
                w.write(c_static, log_ns, ts.serialize_cdr(static, "tf2_msgs/msg/TFMessage"))
            last_ns = log_ns
            k = len(rec.ranges)
            scan = t["sensor_msgs/msg/LaserScan"](
                header=header(sec, "laser"), angle_min=-FOV / 2, angle_max=-FOV / 2 + FOV / k * (k - 1),
                angle_increment=FOV / k, time_increment=0.0, scan_time=0.0, range_min=0.01, range_max=NO_RETURN_M,
                ranges=rec.ranges.astype(np.float32), intensities=np.zeros(0, dtype=np.float32))
            x, y, yaw = (float(v) for v in rec.odom)
            pose_cov = np.zeros(36, dtype=np.float64)
            odom = t["nav_msgs/msg/Odometry"](
                header=header(sec, "odom"), child_frame_id="base_link",
                pose=t["geometry_msgs/msg/PoseWithCovariance"](
                    pose=t["geometry_msgs/msg/Pose"](position=t["geometry_msgs/msg/Point"](x=x, y=y, z=0.0),
                                                     orientation=quat(x=0.0, y=0.0, z=math.sin(yaw / 2),
                                                                      w=math.cos(yaw / 2))),
                    covariance=pose_cov),
                twist=t["geometry_msgs/msg/TwistWithCovariance"](
                    twist=t["geometry_msgs/msg/Twist"](linear=vec(x=0.0, y=0.0, z=0.0),
                                                       angular=vec(x=0.0, y=0.0, z=0.0)),
                    covariance=pose_cov.copy()))
            # odometry and TF first: a consumer looking up odom -> base_link at the scan's stamp finds it
            w.write(c_odom, log_ns, ts.serialize_cdr(odom, "nav_msgs/msg/Odometry"))
            w.write(c_tf, log_ns, ts.serialize_cdr(t["tf2_msgs/msg/TFMessage"](
                transforms=[tf(sec, "odom", "base_link", x, y, yaw)]), "tf2_msgs/msg/TFMessage"))
            w.write(c_scan, log_ns, ts.serialize_cdr(scan, "sensor_msgs/msg/LaserScan"))
            n += 1
            if max_scans is not None and n >= max_scans:
                break
    return n
