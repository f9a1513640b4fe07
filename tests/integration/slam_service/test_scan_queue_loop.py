"""The SLAM service's real scan path (SlamLoop: DDS callback -> ScanQueue -> worker -> SlamEngine) under
scans arriving faster than it can process them: the oldest waiting scans are dropped and counted, at most
``queue_size`` wait, and every received scan is either processed or counted as dropped.

No assertion depends on how fast the machine is: the worker is held on the engine lock (the same lock
the RPC handlers take) while a burst arrives, so exactly which scans are dropped is fixed.
"""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from robonix_api.dds import DdsNode, LaserScan, OccupancyGrid
from robonix_api.dds.convert import laser_scan
from robonix_api.upstream import Binding
from robonix_eval.synthetic import Recording, apartment_world, drive
from slam_service.config import Frames
from slam_service.core import SlamEngine
from slam_service.loop import ScanTiming, SlamLoop

from .conftest import wait_until

pytestmark = pytest.mark.integration
QUEUE = 4


@pytest.fixture(scope="module")
def rec() -> Recording:
    return drive(apartment_world(), seed=6)


@pytest.fixture
def node() -> Iterator[DdsNode]:
    n = DdsNode(name="slam_queue_test")
    yield n
    n.close()


class Feed:
    """A SlamLoop on its own topics; TF goes straight into the loop's buffer (no DDS timing involved)."""

    def __init__(self, node: DdsNode, rec: Recording) -> None:
        self.rec = rec
        self.timings: list[ScanTiming] = []
        bindings = {"scan": Binding("scan", "/queue_test/scan", "reliable"),
                    "odom": Binding("odom", "/queue_test/odom", "reliable")}
        self.loop = SlamLoop(node, bindings, Frames(), SlamEngine(),
                             node.create_publisher("/queue_test/map", OccupancyGrid, "transient_local"),
                             use_sim_time=False, map_period_s=1.0, tf_period_s=0.1, queue_size=QUEUE,
                             on_scan_done=self.timings.append)
        self.loop.tf.set_pose2d("base_link", "laser", 0.0, 0.0, 0.0, static=True)
        self.loop.set_integrating(True)
        self.scan_pub = node.create_publisher("/queue_test/scan", LaserScan, "reliable")

    def msg(self, k: int) -> LaserScan:
        """Scan ``k`` as the lidar sends it; its odometry is in TF before the scan arrives."""
        s, o = self.rec.scans[k], self.rec.odom[k]
        self.loop.tf.set_pose2d("odom", "base_link", *map(float, o), stamp=s.stamp)
        return laser_scan(s.ranges, s.angle_min, s.angle_increment, range_min=s.range_min,
                          range_max=s.range_max, stamp=s.stamp, frame_id="laser")

    def count(self, key: str) -> int:
        return int(self.loop.stats().get(key, 0))


def test_a_burst_while_the_worker_is_busy_drops_exactly_the_oldest(node: DdsNode, rec: Recording) -> None:
    feed = Feed(node, rec)
    loop = feed.loop
    try:
        feed.scan_pub.publish(feed.msg(0))  # over DDS: the subscription is wired to the queue
        wait_until(lambda: feed.count("scans_processed") == 1, 60, "the first scan was processed")
        with loop.lock:  # the worker is busy (an RPC holds the engine): scans pile up
            loop._on_scan(feed.msg(1))
            wait_until(lambda: len(loop._queue) == 0, 30, "the worker took scan 1 and waits for the engine")
            for k in range(2, 12):  # 10 scans arrive while it waits
                loop._on_scan(feed.msg(k))
            s = loop.stats()
            assert s["scans_dropped_behind"] == 10 - QUEUE
            assert s["queue_high_water"] == QUEUE
            assert len(loop._queue) == QUEUE
        wait_until(lambda: feed.count("scans_processed") == 2 + QUEUE, 60, "the backlog was worked off")
        assert loop.engine.stats.scans_received == 2 + QUEUE
        # the newest scans were kept, the oldest dropped
        assert loop._last_stamp == pytest.approx(rec.scans[11].stamp, abs=1e-6)
        assert len(feed.timings) == 2 + QUEUE
        assert all(t.wait_s >= 0 and t.process_s > 0 and t.handle_s >= t.process_s and t.process_cpu_s >= 0
                   for t in feed.timings)
    finally:
        loop.close()


def test_every_received_scan_is_processed_or_counted_as_dropped(node: DdsNode, rec: Recording) -> None:
    feed = Feed(node, rec)
    loop = feed.loop
    n = 300
    try:
        for k in range(n):  # 30 s of scans as fast as the callback takes them: far faster than real time
            loop._on_scan(feed.msg(k))
            assert len(loop._queue) <= QUEUE
        wait_until(lambda: feed.count("scans_processed") + feed.count("scans_dropped_behind") == n, 120,
                   lambda: f"all scans accounted for: {loop.stats()}")
        s = loop.stats()
        assert s["scans_received"] == n
        assert s["queue_high_water"] <= QUEUE
        assert s.get("worker_errors", 0) == 0
        assert loop.engine.stats.scans_received == s["scans_processed"] == len(feed.timings)
        # the last scan is never the one dropped
        assert loop._last_stamp == pytest.approx(rec.scans[n - 1].stamp, abs=1e-6)
    finally:
        loop.close()
