"""Two processes on the suite's own domain: /scan, /map (late joiner), /tf + /tf_static, /clock."""

from __future__ import annotations

import math
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest
from support.wait import wait_until

from robonix_api.dds import DdsNode, LaserScan, OccupancyGrid, SimClock, TfBuffer
from robonix_api.dds.convert import msg_to_grid, scan_to_numpy

from .dds_helpers import stop_process

pytestmark = pytest.mark.integration


def test_scan_best_effort(peer: subprocess.Popen, node: DdsNode) -> None:
    got: list[LaserScan] = []
    lock = threading.Lock()

    def cb(m: LaserScan) -> None:
        with lock:
            got.append(m)

    node.create_subscription("/scan", LaserScan, cb, "best_effort")
    wait_until(lambda: len(got) >= 3, 20.0, "three /scan messages from the peer process")
    scan = got[-1]
    angles, ranges = scan_to_numpy(scan)
    assert scan.header.frame_id == "laser"
    assert ranges.size == 360
    assert np.allclose(ranges, np.arange(360) * 0.01, atol=1e-6)
    assert angles[0] == pytest.approx(-math.pi)
    assert angles[1] - angles[0] == pytest.approx(2 * math.pi / 360)


def test_map_latched_late_subscriber(peer: subprocess.Popen, node: DdsNode) -> None:
    # the peer published its maps before printing READY, long before this subscriber exists
    msg = node.wait_for_message("/map", OccupancyGrid, timeout_s=20.0, qos="latched")
    assert msg is not None, "late subscriber did not receive the latched map"
    grid = msg_to_grid(msg)
    assert grid.data.shape == (300, 400)
    assert grid.resolution == pytest.approx(0.05)
    assert (grid.origin_x, grid.origin_y) == pytest.approx((-1.0, -2.0))
    assert grid.data[0, :5].tolist() == [-1, 0, 100, 7, -1]
    assert int(grid.data[1, 0]) == 42  # the last of the two maps, not the first


def test_volatile_subscriber_gets_no_old_map(peer: subprocess.Popen, node: DdsNode) -> None:
    assert node.wait_for_message("/map", OccupancyGrid, timeout_s=1.0, qos="reliable") is None


def test_tf_and_tf_static(peer: subprocess.Popen, node: DdsNode) -> None:
    buf = TfBuffer(node)
    try:
        wait_until(lambda: buf.can_transform("map", "laser"), 20.0,
                   lambda: f"map->laser; frames so far: {buf.frames()}")
        tf = buf.lookup_transform("map", "laser")
        x, y, yaw = tf.to_pose2d()
        k = round((tf.stamp - 1000.0) / 0.02)
        assert yaw == pytest.approx(math.pi / 2)
        assert (x, y) == pytest.approx((1.0 + 0.01 * k, 0.2), abs=1e-6)
    finally:
        buf.close()


def test_clock(peer: subprocess.Popen, node: DdsNode) -> None:
    clock = SimClock(node, use_sim_time=True)
    try:
        assert clock.now() == 0.0 or clock.now() >= 1000.0
        assert clock.wait_for_first_tick(timeout=20.0)
        t0 = clock.now()
        assert t0 >= 1000.0
        assert clock.sleep_until(t0 + 0.1, timeout=20.0)
        assert clock.now() >= t0 + 0.1
        assert clock.now_msg().sec >= 1000
    finally:
        clock.close()
    wall = SimClock(None, use_sim_time=False)
    assert wall.wait_for_first_tick(0)
    assert wall.now() > 1e9


def test_peer_stops_cleanly_by_pid() -> None:
    """A fresh peer exits on SIGTERM (sent to its PID) within the deadline, leaving nothing behind."""
    proc = subprocess.Popen([sys.executable, str(Path(__file__).with_name("dds_peer.py"))], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        assert proc.stdout.readline().strip() == "READY"
        proc.terminate()
        assert proc.wait(timeout=20) == 0
    finally:
        stop_process(proc)
