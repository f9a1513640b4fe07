"""QoS presets and publish-time validation of wrongly-shaped messages."""

from __future__ import annotations

import numpy as np
import pytest
from support.wait import wait_until

from robonix_api.dds import (
    DdsNode,
    LaserScan,
    OccupancyGrid,
    Odometry,
    TFMessage,
    Twist,
)
from robonix_api.dds.messages import Header, PoseWithCovariance, Time


@pytest.mark.parametrize(("msg", "exc", "field"), [
    (Odometry(pose=PoseWithCovariance(covariance=np.zeros(35))), ValueError, "Odometry.pose.covariance"),
    (LaserScan(angle_min="0.5"), TypeError, "LaserScan.angle_min"),
    (LaserScan(ranges=np.array(["1", "2"])), TypeError, "LaserScan.ranges"),
    (LaserScan(ranges=np.array([1 + 2j])), TypeError, "LaserScan.ranges"),
    (LaserScan(ranges=np.zeros((2, 3), np.float32)), ValueError, "LaserScan.ranges"),
    (LaserScan(ranges=[1.0, None]), TypeError, "LaserScan.ranges"),
    (OccupancyGrid(data=np.zeros(4, np.float32)), TypeError, "OccupancyGrid.data"),
    (OccupancyGrid(data=np.array([0, 300], np.int16)), ValueError, "OccupancyGrid.data"),
    (LaserScan(header=Header(stamp=Time(sec=-1, nanosec=-5))), ValueError, "LaserScan.header.stamp.nanosec"),
    (LaserScan(header=Header(frame_id=5)), TypeError, "LaserScan.header.frame_id"),
    (TFMessage(transforms=[Twist()]), TypeError, "TFMessage.transforms[0]"),
])
def test_bad_messages_rejected_at_publish(node: DdsNode, msg: object, exc: type, field: str) -> None:
    pub = node.create_publisher("/bad_" + type(msg).__name__.lower(), type(msg), "best_effort")
    with pytest.raises(exc) as e:
        pub.publish(msg)
    assert field in str(e.value)


def test_wrong_message_type(node: DdsNode) -> None:
    pub = node.create_publisher("/cmd_vel_t", Twist)
    with pytest.raises(TypeError, match="Twist"):
        pub.publish(LaserScan())


def test_numeric_inputs_are_accepted(node: DdsNode) -> None:
    """Python ints and float64 arrays are published (converted, not refused) and arrive as the ROS types."""
    scans: list[LaserScan] = []
    maps: list[OccupancyGrid] = []
    sub = node.create_subscription("/ok_scan", LaserScan, scans.append, "reliable")
    pub = node.create_publisher("/ok_scan", LaserScan, "reliable")
    assert pub.wait_for_subscribers(1, 20.0), "no reader matched /ok_scan"
    pub.publish(LaserScan(ranges=[1, 2, 3]))  # ints into float32
    pub.publish(LaserScan(ranges=np.ones(360)))  # float64 array into float32
    gpub = node.create_publisher("/ok_map", OccupancyGrid, "latched")
    gpub.publish(OccupancyGrid(data=[0, 100, -1]))
    gsub = node.create_subscription("/ok_map", OccupancyGrid, maps.append, "latched")  # late: latched
    try:
        wait_until(lambda: len(scans) >= 2, 20.0, lambda: f"two scans on /ok_scan, got {len(scans)}")
        wait_until(lambda: maps, 20.0, "the latched map on /ok_map")
    finally:
        sub.close()
        gsub.close()
    assert scans[0].ranges.dtype == np.float32
    assert scans[0].ranges.tolist() == [1.0, 2.0, 3.0]
    assert scans[1].ranges.shape == (360,)
    assert np.all(scans[1].ranges == 1.0)
    assert maps[0].data.tolist() == [0, 100, -1]
