"""`rbnx record` survives a crash and stamps each message: a SIGKILLed recorder leaves an MCAP file that
mcap's own reader reads up to the last flush; consecutive /odom log times differ; ``--format rosbag2``
writes a folder rosbags' AnyReader opens and decodes with its own message definitions."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
from pathlib import Path

import pytest
from support.procs import wait_until

from rbnx.record import McapRecorder, read_truncated
from rbnx.rosmsg import KNOWN
from robonix_api.dds import Clock, DdsNode, Odometry, Time

pytestmark = pytest.mark.timeout(180)


def _odom(i: int) -> Odometry:
    o = Odometry()
    o.header.stamp, o.header.frame_id, o.child_frame_id = Time.from_sec(10.0 + 0.02 * i), "odom", "base_link"
    o.pose.pose.position.x = 0.01 * i
    return o


class _Publisher:
    """/odom and /clock at ~50 Hz from a thread until stopped (a recorder may join at any time)."""

    def __init__(self, node: DdsNode) -> None:
        self.odom = node.create_publisher("/odom", Odometry, "reliable")
        self.clock = node.create_publisher("/clock", Clock, "best_effort")
        self.sent = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self) -> None:
        while not self._stop.wait(0.02):
            self.clock.publish(Clock(clock=Time.from_sec(10.0 + 0.02 * self.sent)))
            self.odom.publish(_odom(self.sent))
            self.sent += 1

    def __enter__(self) -> _Publisher:
        self._thread.start()
        return self

    def __exit__(self, *_: object) -> None:
        self._stop.set()
        self._thread.join(5.0)


def _odom_log_times(path: Path) -> list[int]:
    return [m.log_time for _s, ch, m in read_truncated(path) if ch.topic == "/odom"]


def test_sigkilled_recorder_leaves_a_readable_file_with_distinct_log_times(tmp_path: Path) -> None:
    out = tmp_path / "run.mcap"
    with DdsNode(name="publisher") as node, _Publisher(node) as pub:
        proc = subprocess.Popen([sys.executable, "-m", "rbnx.cli", "record", "-q", "-o", str(out), "/odom", "/clock"],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True)
        try:
            # 150 /odom messages flushed to disk (the reader sees them in the still-open file), then SIGKILL
            wait_until(lambda: out.exists() and len(_odom_log_times(out)) >= 150, 120,
                       lambda: f"{len(_odom_log_times(out)) if out.exists() else 'no file'} /odom on disk")
            on_disk = len(_odom_log_times(out))
        finally:
            os.kill(proc.pid, signal.SIGKILL)
            proc.wait(10)
        assert pub.sent >= on_disk
    times = _odom_log_times(out)
    assert len(times) >= on_disk >= 150
    assert times == sorted(times)
    distinct = sum(b != a for a, b in zip(times, times[1:], strict=False)) / (len(times) - 1)
    assert distinct >= 0.9, f"only {distinct:.0%} of consecutive /odom log times differ"
    # the file is cut short (no footer): the seeking reader refuses, the non-seeking one reads it
    seqs = [m.sequence for _s, ch, m in read_truncated(out) if ch.topic == "/odom"]
    assert seqs == list(range(len(seqs)))


def test_read_truncated_stops_at_any_cut(tmp_path: Path) -> None:
    """Every prefix of a flushed recording reads without raising, and longer prefixes hold no fewer messages."""
    out = tmp_path / "run.mcap"
    rec = McapRecorder(out, [KNOWN["/odom"]], flush_s=0.05)
    rec.start()
    with DdsNode(name="publisher") as node:
        odom = node.create_publisher("/odom", Odometry, "reliable")
        assert odom.wait_for_subscribers(1, 30.0)
        for i in range(40):
            odom.publish(_odom(i))
            threading.Event().wait(0.01)
        wait_until(lambda: rec.counts["/odom"] == 40, 30, lambda: f"recorder counts {rec.counts}")
    rec.stop()
    data = out.read_bytes()
    cut = tmp_path / "cut.mcap"
    previous = 0
    for n in range(0, len(data), max(1, len(data) // 97)):
        cut.write_bytes(data[:n])
        got = sum(1 for _ in read_truncated(cut))
        assert got >= previous
        previous = got
    assert sum(1 for _ in read_truncated(out)) == 40


def test_rosbag2_folder_opens_with_rosbags_anyreader(tmp_path: Path) -> None:
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    bag = tmp_path / "bag"
    proc = subprocess.Popen([sys.executable, "-m", "rbnx.cli", "record", "-q", "--format", "rosbag2", "-o", str(bag),
                             "/odom", "/clock"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        with DdsNode(name="publisher") as node, _Publisher(node):
            wait_until(lambda: (bag / "metadata.yaml").exists() and "message_count: 0\n" not in (
                bag / "metadata.yaml").read_text(), 60, "metadata.yaml with messages")
            threading.Event().wait(0.5)
            proc.send_signal(signal.SIGINT)
            _out, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(10)
    assert proc.returncode == 0, err
    assert sorted(p.name for p in bag.iterdir()) == ["bag_0.mcap", "metadata.yaml"]
    store = get_typestore(Stores.ROS2_HUMBLE)  # rosbags' own definitions, not the schema we wrote
    with AnyReader([bag], default_typestore=store) as reader:
        conns = {c.topic: c for c in reader.connections}
        assert {t: c.msgtype for t, c in conns.items()} == {"/odom": "nav_msgs/msg/Odometry",
                                                            "/clock": "rosgraph_msgs/msg/Clock"}
        xs = [reader.deserialize(raw, c.msgtype).pose.pose.position.x
              for c, _t, raw in reader.messages(connections=[conns["/odom"]])]
        assert reader.message_count == sum(c.msgcount for c in reader.connections)
    assert len(xs) >= 2
    assert xs == sorted(xs)
    assert conns["/odom"].msgcount == len(xs)


def test_rosbag2_refuses_an_existing_folder(tmp_path: Path) -> None:
    (tmp_path / "bag").mkdir()
    r = subprocess.run([sys.executable, "-m", "rbnx.cli", "record", "--format", "rosbag2", "-o", "bag"],
                       cwd=tmp_path, capture_output=True, text=True, timeout=60)
    assert r.returncode == 2
    assert r.stderr.strip() == "rbnx record: --output bag: exists already; give a new bag folder name"
