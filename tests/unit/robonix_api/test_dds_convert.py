"""Topic names and the numpy converters, without a DDS participant (the node itself, its callbacks, close
and errors: tests/integration/robonix_api/test_dds_node_convert.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from robonix_api.dds import LaserScan, OccupancyGrid, Odometry, dds_topic_name
from robonix_api.dds.convert import (
    grid_to_msg,
    laser_scan,
    msg_to_grid,
    odometry,
    odometry_to_numpy,
    pose_to_xyyaw,
    scan_to_numpy,
    twist,
    twist_to_tuple,
    xyyaw_to_pose,
)
from robonix_common.grid import GridMap


def test_topic_names() -> None:
    assert dds_topic_name("/scan") == "rt/scan"
    assert dds_topic_name("map") == "rt/map"
    assert dds_topic_name("/robot1/cmd_vel") == "rt/robot1/cmd_vel"
    with pytest.raises(ValueError, match="invalid topic name '/'"):
        dds_topic_name("/")


def test_grid_roundtrip_fast() -> None:
    data = np.random.default_rng(0).integers(-1, 101, size=(2000, 2000)).astype(np.int8)
    g = GridMap(data, 0.05, -50.0, -40.0, 0.3, "map")
    msg = grid_to_msg(g, 12.5)
    assert (msg.info.width, msg.info.height) == (2000, 2000)
    assert msg.header.stamp.sec == 12
    back = msg_to_grid(OccupancyGrid.deserialize(msg.serialize()))
    assert np.array_equal(back.data, data)
    assert (back.origin_x, back.origin_y, back.origin_yaw) == pytest.approx((-50.0, -40.0, 0.3))
    assert back.resolution == pytest.approx(0.05)
    bad = grid_to_msg(g)
    bad.info.width = 10
    with pytest.raises(ValueError, match="cells"):
        msg_to_grid(bad)


def test_scan_builder() -> None:
    s = laser_scan(np.linspace(1, 2, 360), -math.pi, 2 * math.pi / 360, range_min=0.05, range_max=12.0,
                   stamp=3.25, frame_id="laser")
    assert s.ranges.dtype == np.float32
    assert s.header.stamp.nanosec == 250_000_000
    assert s.angle_max == pytest.approx(-math.pi + 359 * 2 * math.pi / 360, abs=1e-6)
    angles, ranges = scan_to_numpy(LaserScan.deserialize(s.serialize()))
    assert angles.shape == ranges.shape == (360,)
    assert ranges[-1] == pytest.approx(2.0)
    with pytest.raises(ValueError, match="intensities has 1 values, ranges has 2"):
        laser_scan([1.0, 2.0], 0.0, 0.1, intensities=[1.0])


def test_pose_and_odometry_helpers() -> None:
    assert pose_to_xyyaw(xyyaw_to_pose(1.0, -2.0, 2.5)) == pytest.approx((1.0, -2.0, 2.5))
    od = odometry(1.0, 2.0, -0.5, 0.1, 0.2, 0.3, stamp=4.0, pose_covariance=np.eye(6))
    pose, vel = odometry_to_numpy(Odometry.deserialize(od.serialize()))
    assert pose == pytest.approx([1.0, 2.0, -0.5])
    assert vel == pytest.approx([0.1, 0.2, 0.3])
    assert od.pose.covariance[7] == 1.0
    assert od.child_frame_id == "base_link"
    assert twist_to_tuple(twist(0.5, -0.1, 1.9)) == (0.5, -0.1, 1.9)
