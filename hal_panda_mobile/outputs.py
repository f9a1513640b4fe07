"""The provider's DDS outputs: /clock, /odom + TF odom->base_link, /scan, /tf_static, ground truth.

Kept apart from the sim loop so the loop only decides *when* to publish, and the bench can drive the
same publishers without an atlas. Messages are ROS 2 types from ``robonix_api.dds``.
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass
from typing import Any

import numpy as np

from hal_panda_mobile.sim import OdomState, ScanResult
from robonix_api.dds import ClockPublisher, StaticTfBroadcaster, TfBroadcaster, make_transform
from robonix_api.dds.convert import laser_scan, odometry
from robonix_api.dds.messages import LaserScan

# Planar odometry covariance (x, y, z, roll, pitch, yaw): z/roll/pitch are not estimated.
_UNUSED = 1e6


def _cov(xy: float, yaw: float) -> np.ndarray:
    return np.diag([xy, xy, _UNUSED, _UNUSED, _UNUSED, yaw]).reshape(-1)


@dataclass(frozen=True)
class FrameNames:
    odom: str
    base_link: str
    laser: str
    world: str


@dataclass(frozen=True)
class Snapshot:
    """What one loop iteration read from the sim (under its lock), published after the lock is released."""

    t: float  # sim time
    stamp: float  # header stamp (sim time, or wall time without use_sim_time)
    odom: OdomState | None = None
    ground_truth: tuple[float, float, float, float, float, float] | None = None
    scan: ScanResult | None = None
    clock: bool = False


class Outputs:
    """Publishers for one INIT; ``close()`` releases the writers (the node belongs to the provider)."""

    def __init__(self, node: Any, frames: FrameNames, *, odom_pub: Any, scan_pub: Any, gt_pub: Any | None,
                 publish_clock: bool, scan_period: float, noisy_odom: bool) -> None:
        self.frames = frames
        self._odom, self._scan, self._gt = odom_pub, scan_pub, gt_pub
        self._clock = ClockPublisher(node) if publish_clock else None
        self._tf = TfBroadcaster(node)
        self._static = StaticTfBroadcaster(node)
        self._scan_period = scan_period
        self._pose_cov = _cov(0.01, 0.01) if noisy_odom else _cov(1e-6, 1e-6)
        self._twist_cov = _cov(0.001, 0.001) if noisy_odom else _cov(1e-6, 1e-6)
        self.counts = {"clock": 0, "odom": 0, "scan": 0, "ground_truth": 0}

    def publish_static(self, mount: tuple[float, float, float, float], stamp: float) -> None:
        """base_link -> laser on /tf_static (latched: late joiners get it too)."""
        x, y, z, yaw = mount
        self._static.send_transform(make_transform(self.frames.base_link, self.frames.laser, x, y, yaw,
                                                   stamp, z=z))

    def publish(self, snap: Snapshot) -> None:
        if snap.clock and self._clock is not None:
            self._clock.publish(snap.t)
            self.counts["clock"] += 1
        if snap.odom is not None:
            self._publish_odom(snap.odom, snap.stamp)
        if snap.ground_truth is not None and self._gt is not None:
            x, y, yaw, vx, vy, wz = snap.ground_truth
            self._gt.publish(odometry(x, y, yaw, vx, vy, wz, stamp=snap.stamp, frame_id=self.frames.world,
                                      child_frame_id=self.frames.base_link))
            self.counts["ground_truth"] += 1
        if snap.scan is not None:
            self._scan.publish(self.scan_msg(snap.scan, snap.stamp))
            self.counts["scan"] += 1

    def _publish_odom(self, o: OdomState, stamp: float) -> None:
        f = self.frames
        self._odom.publish(odometry(o.x, o.y, o.yaw, o.vx, o.vy, o.wz, stamp=stamp, frame_id=f.odom,
                                    child_frame_id=f.base_link, pose_covariance=self._pose_cov,
                                    twist_covariance=self._twist_cov))
        self._tf.send(f.odom, f.base_link, o.x, o.y, o.yaw, stamp)
        self.counts["odom"] += 1

    def scan_msg(self, s: ScanResult, stamp: float) -> LaserScan:
        """ROS LaserScan: +inf = no return within range_max, -inf = closer than range_min (REP-117)."""
        return laser_scan(s.ranges, s.angle_min, s.angle_increment, range_min=s.range_min,
                          range_max=s.range_max, stamp=stamp, frame_id=self.frames.laser,
                          scan_time=self._scan_period, time_increment=0.0)

    def close(self) -> None:
        for item in (self._clock, self._tf, self._static, self._odom, self._scan, self._gt):
            if item is not None:
                with contextlib.suppress(Exception):  # closing must never stop the teardown of the rest
                    item.close()


__all__ = ["FrameNames", "Outputs", "Snapshot"]
