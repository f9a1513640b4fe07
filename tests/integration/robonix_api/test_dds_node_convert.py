"""Node behaviour in one process: callbacks, close, errors, static TF (the converters alone:
tests/unit/robonix_api/test_dds_convert.py)."""

from __future__ import annotations

import logging
import math
import threading

import pytest
from support.wait import wait_until

from robonix_api.dds import DdsNode, LaserScan, Odometry, Twist
from robonix_api.dds.convert import (
    odometry,
    twist,
)


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
