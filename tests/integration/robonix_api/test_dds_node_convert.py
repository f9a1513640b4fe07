"""Node behaviour in one process (callbacks, close, errors) and the numpy converters."""

from __future__ import annotations

import logging
import math
import threading

import numpy as np
import pytest
from support.wait import wait_until

from robonix_api.dds import DdsNode, LaserScan, OccupancyGrid, Odometry, Twist, dds_topic_name
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
    with pytest.raises(ValueError):
        dds_topic_name("/")


def test_callback_exception_is_logged_not_fatal(node: DdsNode, caplog: pytest.LogCaptureFixture) -> None:
    seen: list[float] = []

    def cb(m: Twist) -> None:
        seen.append(m.linear.x)
        if m.linear.x == 1.0:
            raise RuntimeError("boom")

    node.create_subscription("/cmd_vel", Twist, cb, "reliable")
    pub = node.create_publisher("/cmd_vel", Twist, "reliable")
    assert pub.wait_for_subscribers(1, 20)
    with caplog.at_level(logging.ERROR, logger="robonix_api.dds.node"):
        pub.publish(twist(1.0))
        wait_until(lambda: 1.0 in seen, 20.0, "the first message")
        pub.publish(twist(2.0))
        wait_until(lambda: 2.0 in seen, 20.0, "the second message after the failing callback")
    assert "boom" in caplog.text


def test_callbacks_on_background_thread_and_close_stops_them(node: DdsNode) -> None:
    threads: list[str] = []
    sub = node.create_subscription("/odom", Odometry, lambda m: threads.append(threading.current_thread().name),
                                   "reliable")
    pub = node.create_publisher("/odom", Odometry, "reliable")
    assert pub.wait_for_subscribers(1, 20)
    pub.publish(odometry(1, 2, 0.5))
    wait_until(lambda: threads, 20.0, "a callback")
    assert threads[0] != threading.current_thread().name
    sub.close()
    sub.close()  # idempotent
    n = len(threads)
    pub.publish(odometry(1, 2, 0.5))
    assert node.wait_for_message("/odom", Odometry, 0.3) is None  # nothing latched on a volatile topic
    assert len(threads) == n


def test_topic_type_conflict_and_closed_node() -> None:
    n = DdsNode(name="conflict")
    n.create_publisher("/x", Twist)
    with pytest.raises(TypeError, match="already used"):
        n.create_publisher("/x", LaserScan)
    n.close()
    n.close()
    with pytest.raises(RuntimeError, match="closed"):
        n.create_publisher("/y", Twist)


def test_wait_for_topic(node: DdsNode) -> None:
    assert not node.wait_for_topic("/nobody_here", Twist, 0.2)
    other = DdsNode(name="other")
    try:
        other.create_publisher("/somebody", Twist, "reliable")
        assert node.wait_for_topic("/somebody", Twist, 20.0)
    finally:
        other.close()


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
    with pytest.raises(ValueError):
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


def test_static_transforms_from_two_publishers_both_survive(node: DdsNode) -> None:
    """Two static broadcasters (e.g. robot description + SLAM) each latch one sample; a late buffer
    must keep both (tf2's static listener depth), not just the most recent one."""
    from robonix_api.dds import StaticTfBroadcaster, TfBuffer

    other = DdsNode(name="second_static")
    try:
        StaticTfBroadcaster(node).send("base_link", "laser", 0.1, 0.0, 0.0, 0.0)
        StaticTfBroadcaster(other).send("odom", "base_link", 1.0, 2.0, 0.5, 0.0)
        late = TfBuffer(node)
        wait_until(lambda: late.can_transform("odom", "laser"), 30.0, "odom->laser from two static publishers")
        x, y, yaw = late.lookup_pose2d("odom", "laser")
        assert abs(yaw - 0.5) < 1e-6
        assert abs(x - (1.0 + 0.1 * math.cos(0.5))) < 1e-6
    finally:
        other.close()
