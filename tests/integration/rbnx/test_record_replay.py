"""rbnx record / replay over real DDS (no simulator): what we publish is what an independent decoder
(mcap-ros2-support, rosbags) reads back, and what replay republishes; our schemas parse as ROS 2 .msg;
a ROS 2 .db3 bag written by rosbags replays with a /clock taken from its log times; CLI errors exit 2."""

from __future__ import annotations

import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from support.procs import wait_until

from rbnx.record import McapRecorder
from rbnx.replay import Replayer, ReplayError, parse_remap
from rbnx.rosmsg import DEFAULT_TOPICS, KNOWN, TYPES, TopicError, parse_topic, schema_text
from robonix_api.dds import Clock, DdsNode, LaserScan, Odometry, TFMessage, Time
from robonix_api.dds.convert import laser_scan
from robonix_api.dds.tf import make_transform

pytestmark = pytest.mark.timeout(120)


def _scan(i: int) -> LaserScan:
    rng = np.random.default_rng(i)
    return laser_scan(rng.uniform(0.2, 8.0, 360), -np.pi, 2 * np.pi / 360, range_min=0.1, range_max=12.0,
                      stamp=10.0 + 0.1 * i, frame_id="laser")


def _odom(i: int) -> Odometry:
    o = Odometry()
    o.header.stamp, o.header.frame_id, o.child_frame_id = Time.from_sec(10.0 + 0.02 * i), "odom", "base_link"
    o.pose.pose.position.x, o.pose.pose.position.y = 0.01 * i, -0.5 * i
    o.twist.twist.linear.x = 0.25
    return o


def _tf(i: int) -> TFMessage:
    return TFMessage(transforms=[make_transform("odom", "base_link", 0.01 * i, 0.0, 0.1 * i, 10.0 + 0.02 * i),
                                 make_transform("map", "odom", 0.5, 0.25, 0.0, 10.0 + 0.02 * i)])


def test_schemas_parse_as_ros2_msg_for_every_type() -> None:
    from mcap_ros2._dynamic import generate_dynamic

    for name, cls in TYPES.items():
        decoders = generate_dynamic(name, schema_text(cls))
        assert name in decoders, name


def test_parse_topic_errors_name_the_topic() -> None:
    assert parse_topic("/scan").msg_type is LaserScan
    assert parse_topic("/front/odom:nav_msgs/Odometry").msg_type is Odometry
    with pytest.raises(TopicError, match="/foo: unknown type"):
        parse_topic("/foo")
    with pytest.raises(TopicError, match="type 'nav_msgs/Nope'"):
        parse_topic("/foo:nav_msgs/Nope")
    with pytest.raises(ReplayError, match="FROM:=TO"):
        parse_remap("/scan")


def _publish_all(node: DdsNode, n: int) -> dict[str, list]:
    pubs = {"/scan": node.create_publisher("/scan", LaserScan, "best_effort"),
            "/odom": node.create_publisher("/odom", Odometry, "reliable"),
            "/tf": node.create_publisher("/tf", TFMessage, "reliable")}
    sent: dict[str, list] = {"/scan": [], "/odom": [], "/tf": []}
    for p in pubs.values():
        assert p.wait_for_subscribers(1, 10.0)
    for i in range(n):
        for topic, make in (("/scan", _scan), ("/odom", _odom), ("/tf", _tf)):
            msg = make(i)
            pubs[topic].publish(msg)
            sent[topic].append(msg)
        threading.Event().wait(0.01)
    return sent


def test_recording_decodes_with_mcap_ros2_support_into_the_published_fields(tmp_path: Path) -> None:
    out = tmp_path / "run.mcap"
    specs = [KNOWN[t] for t in ("/scan", "/odom", "/tf")]
    rec = McapRecorder(out, specs)
    rec.start()
    with DdsNode(name="publisher") as node:
        sent = _publish_all(node, 30)
        wait_until(lambda: rec.counts["/odom"] == 30 and rec.counts["/tf"] == 30 and rec.counts["/scan"] >= 25,
                   30, lambda: f"recorder counts {rec.counts}")
    rec.stop()

    got: dict[str, list] = {"/scan": [], "/odom": [], "/tf": []}
    with open(out, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        assert reader.get_header().profile == "ros2"
        for schema, channel, _msg, decoded in reader.iter_decoded_messages():
            assert schema.encoding == "ros2msg"
            assert channel.message_encoding == "cdr"
            got[channel.topic].append(decoded)
    assert {s.name for s in reader.get_summary().schemas.values()} == {
        "sensor_msgs/msg/LaserScan", "nav_msgs/msg/Odometry", "tf2_msgs/msg/TFMessage"}

    scans = {(m.header.stamp.sec, m.header.stamp.nanosec): m for m in sent["/scan"]}
    for m in got["/scan"]:
        ref = scans[(m.header.stamp.sec, m.header.stamp.nanosec)]
        assert m.header.frame_id == "laser"
        np.testing.assert_array_equal(np.asarray(m.ranges, np.float32), ref.ranges)
        assert (m.angle_min, m.angle_increment, m.range_max) == pytest.approx(
            (ref.angle_min, ref.angle_increment, ref.range_max), abs=0, rel=1e-7)
    for m, ref in zip(got["/odom"], sent["/odom"], strict=True):
        assert (m.header.frame_id, m.child_frame_id) == ("odom", "base_link")
        assert (m.pose.pose.position.x, m.pose.pose.position.y, m.twist.twist.linear.x) == (
            ref.pose.pose.position.x, ref.pose.pose.position.y, ref.twist.twist.linear.x)
        assert list(m.pose.covariance) == list(ref.pose.covariance)
    for m, ref in zip(got["/tf"], sent["/tf"], strict=True):
        assert [(t.header.frame_id, t.child_frame_id, t.transform.translation.x, t.transform.rotation.z)
                for t in m.transforms] == [(t.header.frame_id, t.child_frame_id, t.transform.translation.x,
                                            t.transform.rotation.z) for t in ref.transforms]


def test_replay_republishes_with_remap_drop_tf_and_clock_from_a_ros2_db3_bag(tmp_path: Path) -> None:
    """A bag written by rosbags (as `ros2 bag record` would, sqlite3 storage) with no /clock topic."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    bag = tmp_path / "bag"
    store = get_typestore(Stores.ROS2_HUMBLE)  # rosbags' own message definitions, not ours
    with Writer(bag, version=8, storage_plugin=StoragePlugin.SQLITE3) as w:
        cs = w.add_connection("/scan", "sensor_msgs/msg/LaserScan", typestore=store)
        ct = w.add_connection("/tf", "tf2_msgs/msg/TFMessage", typestore=store)
        for i in range(20):
            t_ns = 1_000_000_000_000 + i * 50_000_000
            w.write(cs, t_ns, _scan(i).serialize())
            w.write(ct, t_ns, _tf(i).serialize())
    (db3,) = bag.glob("*.db3")

    got: dict[str, list] = {"/robot/scan": [], "/tf": [], "/clock": []}
    with DdsNode(name="listener") as node:
        node.create_subscription("/robot/scan", LaserScan, got["/robot/scan"].append, "best_effort", 100)
        node.create_subscription("/tf", TFMessage, got["/tf"].append, "reliable", 100)
        node.create_subscription("/clock", Clock, got["/clock"].append, "best_effort", 100)
        rep = Replayer(db3, rate=4.0, remaps={"/scan": "/robot/scan"}, drop_tf=["odom"], delay_s=1.5)
        stats = rep.run()
        # /scan keeps its best-effort QoS on the remapped topic: allow a lost sample on a busy machine
        wait_until(lambda: len(got["/robot/scan"]) >= 18 and len(got["/tf"]) == 20, 20,
                   lambda: f"replayed {[(k, len(v)) for k, v in got.items()]}")
    assert stats.published == {"/robot/scan": 20, "/tf": 20}
    for m in got["/robot/scan"]:
        i = round((m.header.stamp.to_sec() - 10.0) / 0.1)
        np.testing.assert_array_equal(m.ranges, _scan(i).ranges)
    assert all([t.child_frame_id for t in m.transforms] == ["base_link"] for m in got["/tf"])
    clocks = [c.clock.to_sec() for c in got["/clock"]]
    assert clocks
    assert clocks == sorted(clocks)
    assert clocks[0] == pytest.approx(1000.0)


def test_replay_of_our_recording_round_trips_and_loops(tmp_path: Path) -> None:
    out = tmp_path / "run.mcap"
    rec = McapRecorder(out, [KNOWN["/odom"], KNOWN["/clock"]])
    rec.start()
    with DdsNode(name="publisher") as node:
        clock = node.create_publisher("/clock", Clock, "best_effort")
        odom = node.create_publisher("/odom", Odometry, "reliable")
        assert odom.wait_for_subscribers(1, 10.0)
        assert clock.wait_for_subscribers(1, 10.0)
        for i in range(10):
            clock.publish(Clock(clock=Time.from_sec(10.0 + 0.02 * i)))
            odom.publish(_odom(i))
            threading.Event().wait(0.01)
        wait_until(lambda: rec.counts["/odom"] == 10, 20, lambda: f"recorder counts {rec.counts}")
    rec.stop()

    got: list[Odometry] = []
    with DdsNode(name="listener") as node:
        node.create_subscription("/odom", Odometry, got.append, "reliable", 100)
        stats = Replayer(out, rate=2.0, loop=False, delay_s=1.5).run()
        wait_until(lambda: len(got) == 10, 20, lambda: f"{len(got)} odometry messages replayed")
    assert [m.pose.pose.position.y for m in got] == [_odom(i).pose.pose.position.y for i in range(10)]
    assert stats.published["/odom"] == 10
    assert stats.published["/clock"] >= 1

    stop = threading.Event()
    looping = Replayer(out, rate=20.0, loop=True, delay_s=0.0)
    t = threading.Thread(target=looping.run, args=(stop,))
    t.start()
    try:
        wait_until(lambda: looping.stats.loops >= 2, 30, "two loops")
    finally:
        stop.set()
        t.join(10)
    assert not t.is_alive()


@pytest.mark.parametrize(("argv", "message"), [
    (["record", "-o", "x.txt"], "must end in .mcap"),
    (["record", "-o", "run.mcap", "/foo", "--discovery-timeout", "0.5"], "/foo: no writer seen in 0.5 s"),
    (["record", "-o", "run.mcap", "/foo:nav_msgs/Nope"], "type 'nav_msgs/Nope'"),
    (["record", "-o", "nodir/run.mcap"], "does not exist"),
    (["record", "-o", "run.mcap", "--duration", "0"], "--duration"),
    (["replay", "missing.mcap"], "no such file"),
    (["replay", "notes.txt"], "not a recording"),
    (["replay", "run.mcap", "--rate", "0"], "--rate: must be > 0"),
    (["replay", "run.mcap", "--remap", "/scan"], "FROM:=TO"),
    (["navigate", "1", "nan"], "y: must be a finite number"),
    (["navigate", "1", "2", "--frame", " "], "--frame: must not be empty"),
    (["navigate", "1", "2", "--timeout", "-1"], "--timeout: must be >= 0"),
    (["dashboard", "--port", "70000"], "--port: must be 0..65535"),
    (["demo", "--dashboard", "70000"], "--dashboard: port must be 0..65535"),
])
def test_cli_errors_are_one_line_and_exit_2(tmp_path: Path, argv: list[str], message: str) -> None:
    (tmp_path / "notes.txt").write_text("x")
    (tmp_path / "run.mcap").write_bytes(b"")
    r = subprocess.run([sys.executable, "-m", "rbnx.cli", *argv], cwd=tmp_path, capture_output=True, text=True,
                       timeout=60)
    assert r.returncode == 2, r.stderr
    assert message in r.stderr
    assert "Traceback" not in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1


def test_record_learns_type_and_qos_of_other_topics_from_their_writers() -> None:
    from rbnx.record import discover_topics

    with DdsNode(name="writers") as node:
        node.create_publisher("/robot/odom", Odometry, "latched")
        node.create_publisher("/robot/scan", LaserScan, "best_effort")
        node.create_publisher("/robot/tf", TFMessage, "reliable")
        specs = discover_topics(["/robot/scan", "/robot/odom", "/robot/tf"], None, 30.0)
    assert [(s.topic, s.msg_type, s.qos) for s in specs] == [
        ("/robot/scan", LaserScan, "best_effort"), ("/robot/odom", Odometry, "latched"),
        ("/robot/tf", TFMessage, "reliable")]


def test_default_topics_match_the_issue_and_the_help_text() -> None:
    from rbnx.record import DEFAULT_TOPIC_NAMES

    assert [s.topic for s in DEFAULT_TOPICS] == ["/scan", "/odom", "/tf", "/tf_static", "/map", "/plan",
                                                  "/cmd_vel", "/clock"] == DEFAULT_TOPIC_NAMES.split()
