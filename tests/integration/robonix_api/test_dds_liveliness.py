"""Writer liveliness across processes: a stopped or killed writer is reported lost within about a lease.

A child process publishes /odom and /tf (map→odom) through DdsNode; the test process reads them and is
told, from the data plane alone, when the child is SIGSTOPped, SIGCONTed and SIGKILLed. Also checks the
QoS stays matchable by a ROS 2 style reader (automatic liveliness, infinite lease) and the env variable's
validation.
"""

from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
import threading

import pytest
from cyclonedds.core import Policy
from cyclonedds.qos import Qos
from cyclonedds.sub import DataReader
from cyclonedds.util import duration
from support.wait import wait_until

from robonix_api.dds import Odometry, TfBuffer
from robonix_api.dds.qos import LIVELINESS_ENV, describe, liveliness_lease_s, qos_profile, writer_qos

from .dds_helpers import stop_process

WRITER = r"""
import sys, time
from robonix_api.dds import DdsNode, Odometry, TfBroadcaster
node = DdsNode(name="liveliness-writer")
pub = node.create_publisher("/live_odom", Odometry, "reliable")
tf = TfBroadcaster(node)
print("READY", flush=True)
k = 0
while True:
    pub.publish(Odometry())
    tf.send("map", "odom", 0.0, 0.0, 0.0, 1.0 + k * 0.05)
    k += 1
    time.sleep(0.05)
"""


@pytest.fixture
def writer_proc():
    proc = subprocess.Popen([sys.executable, "-c", WRITER], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    try:
        line = proc.stdout.readline()
        if line.strip() != "READY":
            pytest.fail(f"writer did not start: {line!r} {proc.stderr.read()[-2000:]}")
        yield proc
    finally:
        if proc.poll() is None:
            os.kill(proc.pid, signal.SIGCONT)
        stop_process(proc)


def test_liveliness_stop_cont_kill_reported_per_writer(node, writer_proc) -> None:
    events: list[tuple[int, bool]] = []
    got = threading.Event()
    sub = node.create_subscription("/live_odom", Odometry, lambda m: got.set(), "reliable",
                                   on_liveliness=lambda h, alive: events.append((h, alive)))
    tf = TfBuffer(node)
    try:
        assert got.wait(20.0), "no odometry from the writer process"
        wait_until(lambda: len(sub.alive_writers()) == 1 and tf.can_transform("map", "odom"), 20.0,
                   "one alive writer and map->odom")
        assert tf.lost_links() == []
        assert not tf.link_lost("odom")

        os.kill(writer_proc.pid, signal.SIGSTOP)
        wait_until(lambda: not sub.alive_writers() and tf.link_lost("odom"), 10.0, "the writer and map->odom lost")
        assert events[-1][1] is False
        assert tf.lost_links() == [("map", "odom")]

        os.kill(writer_proc.pid, signal.SIGCONT)
        wait_until(lambda: len(sub.alive_writers()) == 1 and not tf.link_lost("odom"), 10.0,
                   "the writer and map->odom back")
        assert events[-1][1] is True

        writer_proc.kill()
        writer_proc.wait(10)
        wait_until(lambda: not sub.alive_writers() and tf.link_lost("odom"), 10.0, "the writer and map->odom lost")
    finally:
        tf.close()
        sub.close()


def test_fresh_data_repairs_a_lost_event_delivered_out_of_order(node, writer_proc) -> None:
    """Cyclone's 'lost' and 'alive again' listener calls come from different threads; if the 'lost' one
    is delivered last (as after our own process was frozen), the next sample must bring the writer back."""
    got = threading.Event()
    sub = node.create_subscription("/live_odom", Odometry, lambda m: got.set(), "reliable")
    tf = TfBuffer(node)
    try:
        assert got.wait(20.0), "no odometry from the writer process"
        wait_until(lambda: len(sub.alive_writers()) == 1 and tf.can_transform("map", "odom"), 20.0,
                   "one alive writer and map->odom")
        (handle,) = sub.alive_writers()
        sub._liveliness_event(handle, False)  # the late 'lost' call, as the listener would make it
        for tf_sub in tf._subs:
            for h in tf_sub.alive_writers():
                tf_sub._liveliness_event(h, False)
        wait_until(lambda: sub.alive_writers() == {handle} and not tf.link_lost("odom"), 10.0,
                   "the same writer alive again and map->odom back")
    finally:
        tf.close()
        sub.close()


def test_liveliness_writer_matches_a_ros2_style_reader(node) -> None:
    """ROS 2 readers ask for AUTOMATIC liveliness with an infinite lease: they must match our writers."""
    pub = node.create_publisher("/live_match", Odometry, "reliable")
    assert describe(pub.qos)["reliability"] == "reliable"
    ros_like = Qos(Policy.Reliability.Reliable(duration(milliseconds=100)),
                   Policy.Liveliness.Automatic(duration(infinite=True)),
                   Policy.DataRepresentation(use_cdrv0_representation=True))
    reader = DataReader(node.participant, node._topic("/live_match", Odometry), ros_like)
    try:
        assert pub.wait_for_subscribers(1, timeout_s=20.0)
        offered = pub._writer.get_qos()[Policy.Liveliness.Automatic]
        assert offered is not None
        assert offered.lease_duration == int(liveliness_lease_s() * 1e9)
    finally:
        reader.__del__()
        pub.close()


def test_liveliness_lease_setting_validated(monkeypatch) -> None:
    assert liveliness_lease_s("") == 0.5
    assert liveliness_lease_s("1.5") == 1.5
    assert math.isinf(liveliness_lease_s("inf"))
    for bad in ("abc", "0", "-1", "nan", "0.01"):
        with pytest.raises(ValueError, match=LIVELINESS_ENV):
            liveliness_lease_s(bad)
    monkeypatch.setenv(LIVELINESS_ENV, "off")
    assert writer_qos(qos_profile("reliable"))[Policy.Liveliness.Automatic] is None
    monkeypatch.setenv(LIVELINESS_ENV, "0.25")
    assert describe(writer_qos(qos_profile("reliable")))["liveliness_lease_s"] == 0.25
