"""Scans are placed at the robot's pose when they were taken, not at the latest pose."""

from __future__ import annotations

import math

import numpy as np

from nav2_wrapper.config import Frames
from nav2_wrapper.inputs import Inputs
from robonix_api.dds import LaserScan, TfBuffer
from robonix_api.dds.convert import laser_scan


def inputs_with_tf() -> Inputs:
    """An Inputs around a TF buffer fed directly (no DDS): only pose_at/core_scan are exercised."""
    inp = Inputs.__new__(Inputs)
    inp.frames = Frames()
    inp.tf = TfBuffer(None)
    inp.tf.set_pose2d("map", "odom", 1.0, 0.0, 0.0, 1.0)
    inp.tf.set_pose2d("base_link", "laser", 0.0, 0.0, 0.0, static=True)
    for k in range(11):  # the base drives +x at 0.5 m/s and turns at 1 rad/s between t=1 and t=2
        t = 1.0 + 0.1 * k
        inp.tf.set_pose2d("odom", "base_link", 0.5 * (t - 1.0), 0.0, t - 1.0, t)
    return inp


def scan_at(stamp: float) -> LaserScan:
    return laser_scan(np.full(8, 2.0, np.float32), -math.pi, math.pi / 4, range_min=0.05, range_max=12.0, stamp=stamp,
                      frame_id="laser")


def test_scan_pose_is_interpolated_at_its_stamp() -> None:
    inp = inputs_with_tf()
    latest = inp.pose_at(2.0, (0.0, 0.0, 0.0))
    assert np.allclose(latest, (1.5, 0.0, 1.0))
    _, laser_pose = inp.core_scan(scan_at(1.5), latest)
    assert np.allclose(laser_pose, (1.25, 0.0, 0.5), atol=1e-9)   # not the latest pose (1.5, 0, 1.0)


def test_scan_newer_than_tf_uses_the_given_pose() -> None:
    inp = inputs_with_tf()
    _, laser_pose = inp.core_scan(scan_at(5.0), (9.0, 9.0, 0.3))
    assert np.allclose(laser_pose, (9.0, 9.0, 0.3))
