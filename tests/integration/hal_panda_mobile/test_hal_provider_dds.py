"""The provider process end to end: DDS topics with ROS 2 type names, /cmd_vel driving, sim contracts
over gRPC (found through the atlas) and one MCP tool call. rtf 2 keeps /cmd_vel (0.5 s sim timeout)
comfortably fresh from a 20 Hz wall-clock publisher whatever the machine's speed."""

from __future__ import annotations

import asyncio
import json
import math
import threading
import time
from collections.abc import Iterator
from typing import Any

import grpc
import numpy as np
import pytest
from cyclonedds.builtin import BuiltinDataReader, BuiltinTopicDcpsPublication, BuiltinTopicDcpsSubscription

from robonix_api.dds import Clock, DdsNode, LaserScan, Odometry, TFMessage, Twist
from robonix_api.dds.convert import twist
from robonix_api.proto_gen import robonix_contracts_pb2_grpc as rpc
from robonix_api.proto_gen import sim_pb2

from .conftest import HalProcess, wait_until

SIM = "robonix/primitive/sim/"
TYPES = {
    "rt/scan": "sensor_msgs::msg::dds_::LaserScan_",
    "rt/odom": "nav_msgs::msg::dds_::Odometry_",
    "rt/tf": "tf2_msgs::msg::dds_::TFMessage_",
    "rt/tf_static": "tf2_msgs::msg::dds_::TFMessage_",
    "rt/clock": "rosgraph_msgs::msg::dds_::Clock_",
    "rt/ground_truth/odom": "nav_msgs::msg::dds_::Odometry_",
}


class Latest:
    """Last message per topic plus a count, filled by DDS callbacks."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.msgs: dict[str, Any] = {}
        self.counts: dict[str, int] = {}

    def cb(self, topic: str) -> Any:
        def on(msg: Any) -> None:
            with self.lock:
                self.msgs[topic] = msg
                self.counts[topic] = self.counts.get(topic, 0) + 1
        return on

    def get(self, topic: str) -> Any:
        with self.lock:
            return self.msgs.get(topic)


@pytest.fixture(scope="module")
def node() -> Iterator[DdsNode]:
    n = DdsNode(name="hal_test")
    yield n
    n.close()


@pytest.fixture(scope="module")
def hal(hal_factory) -> Iterator[HalProcess]:  # type: ignore[no-untyped-def]
    p: HalProcess = hal_factory("hal_dds")
    yield p
    assert p.stop() == 0
    log = p.log()
    assert "sim loop iteration failed" not in log, log[-4000:]
    assert "Traceback" not in log, log[-4000:]


@pytest.fixture(scope="module")
def seen(hal: HalProcess, node: DdsNode) -> Latest:
    """INIT (held), check frames resolve before ACTIVATE, then ACTIVATE."""
    latest = Latest()
    for topic, typ, qos in (("/scan", LaserScan, "best_effort"), ("/odom", Odometry, "reliable"),
                            ("/tf", TFMessage, "reliable"), ("/tf_static", TFMessage, "latched"),
                            ("/clock", Clock, "clock"), ("/ground_truth/odom", Odometry, "reliable")):
        node.create_subscription(topic, typ, latest.cb(topic), qos)
    assert hal.init({"scene": "apartment", "real_time_factor": 2.0}) == (True, "inactive", "")
    wait_until(lambda: latest.get("/odom") and latest.get("/tf_static") and latest.get("/scan"), 60,
               "held /odom, /tf_static and /scan before ACTIVATE")
    held_t = latest.get("/odom").header.stamp.to_sec()
    assert held_t == 0.0
    assert hal.activate() == (True, "active", "")
    wait_until(lambda: latest.get("/clock") and latest.get("/clock").clock.to_sec() > 1.0, 60, "/clock > 1 s")
    return latest


def gt(hal: HalProcess) -> sim_pb2.GetGroundTruth_Response:
    return hal.stub(SIM + "ground_truth", rpc.RobonixPrimitiveSimGroundTruthStub).GetGroundTruth(
        sim_pb2.GetGroundTruth_Request(), timeout=30)


def drive(node: DdsNode, vx: float, vy: float, wz: float, until: Any, timeout_s: float = 90) -> None:
    """Publish a twist at ~20 Hz (wall) until ``until()`` holds; then a zero twist."""
    pub = node.create_publisher("/cmd_vel", Twist, "reliable")
    try:
        pub.wait_for_subscribers(1, 30)
        deadline = time.monotonic() + timeout_s
        while not until():
            assert time.monotonic() < deadline, "robot did not get there in time"
            pub.publish(twist(vx, vy, wz))
            time.sleep(0.05)
        pub.publish(twist())
    finally:
        pub.close()


def test_topics_types_and_frames(seen: Latest, node: DdsNode) -> None:
    wait_until(lambda: all(seen.get(t) for t in ("/scan", "/odom", "/tf", "/clock", "/ground_truth/odom")), 60,
               "every topic while active")
    scan: LaserScan = seen.get("/scan")
    assert scan.header.frame_id == "laser"
    assert len(scan.ranges) == 360
    assert math.isclose(scan.angle_min, -math.pi, rel_tol=1e-6)
    assert math.isclose(scan.angle_increment, 2 * math.pi / 360, rel_tol=1e-5)
    assert math.isclose(scan.range_min, 0.05, rel_tol=1e-6)
    assert math.isclose(scan.range_max, 12.0)
    assert math.isclose(scan.scan_time, 0.1, rel_tol=1e-6)
    finite = np.isfinite(np.asarray(scan.ranges))
    assert finite.sum() > 300  # a closed apartment: almost every beam hits something
    odom: Odometry = seen.get("/odom")
    assert (odom.header.frame_id, odom.child_frame_id) == ("odom", "base_link")
    tf_static = seen.get("/tf_static").transforms
    assert [(t.header.frame_id, t.child_frame_id) for t in tf_static] == [("base_link", "laser")]
    assert math.isclose(tf_static[0].transform.translation.z, 0.35)
    tf = seen.get("/tf").transforms
    assert (tf[0].header.frame_id, tf[0].child_frame_id) == ("odom", "base_link")
    gto: Odometry = seen.get("/ground_truth/odom")
    assert gto.header.frame_id == "world"
    # ROS 2 type names as the DDS discovery data carries them
    pubs = {s.topic_name: s.type_name for s in BuiltinDataReader(node.participant, BuiltinTopicDcpsPublication)
            .read(N=500)}
    for topic, type_name in TYPES.items():
        assert pubs.get(topic) == type_name, (topic, pubs.get(topic))
    subs = {s.topic_name: s.type_name for s in BuiltinDataReader(node.participant, BuiltinTopicDcpsSubscription)
            .read(N=500)}
    assert subs.get("rt/cmd_vel") == "geometry_msgs::msg::dds_::Twist_"


def test_cmd_vel_moves_robot_and_odom_follows(seen: Latest, hal: HalProcess, node: DdsNode) -> None:
    start = gt(hal)
    drive(node, 0.4, 0.0, 0.0, lambda: gt(hal).x > start.x + 0.3)
    end = gt(hal)
    assert end.x - start.x > 0.3
    assert abs(end.y - start.y) < 0.05
    assert end.sim_time > start.sim_time
    # noise off: /odom (odom frame == world frame by default) follows ground truth
    wait_until(lambda: seen.get("/odom").header.stamp.to_sec() > end.sim_time, 30, "a newer /odom")
    o = seen.get("/odom").pose.pose.position
    assert abs(o.x - end.x) < 0.1
    assert abs(o.y - end.y) < 0.05


def test_collision_teleport_spawn_reset_and_mcp(seen: Latest, hal: HalProcess, node: DdsNode) -> None:
    teleport = hal.stub(SIM + "teleport", rpc.RobonixPrimitiveSimTeleportStub)
    collisions = hal.stub(SIM + "collisions", rpc.RobonixPrimitiveSimCollisionsStub)
    # into the coffee table (centre (2.5, 2.0), 1.0 x 0.6): refused, naming it
    r = teleport.Teleport(sim_pb2.Teleport_Request(x=2.5, y=2.0, theta=0.0), timeout=30)
    assert not r.ok
    assert "coffee_table" in r.detail
    with pytest.raises(grpc.RpcError) as exc:
        teleport.Teleport(sim_pb2.Teleport_Request(x=float("nan"), y=2.0), timeout=30)
    assert exc.value.code() == grpc.StatusCode.INVALID_ARGUMENT
    assert "x:" in exc.value.details()
    # drive sideways (holonomic) into the table: a collision event, and no tunnelling through it
    assert teleport.Teleport(sim_pb2.Teleport_Request(x=2.5, y=3.0, theta=0.0), timeout=30).ok
    t0 = gt(hal).sim_time

    def hit() -> bool:
        return collisions.GetCollisions(sim_pb2.GetCollisions_Request(since_sim_time=t0), timeout=30).count > 0

    drive(node, 0.0, -0.5, 0.0, hit)
    ev = collisions.GetCollisions(sim_pb2.GetCollisions_Request(since_sim_time=t0), timeout=30).events[0]
    assert ev.other_geom == "coffee_table"
    wait_until(lambda: gt(hal).vy > -0.01, 30, "the base to stop after the cmd_vel timeout")
    assert gt(hal).y > 2.3 + 0.25 - 0.05  # table edge + half width, minus contact slop

    # a spawned box shows up in the scan (beam 180 looks straight ahead)
    assert teleport.Teleport(sim_pb2.Teleport_Request(x=2.5, y=4.0, theta=0.0), timeout=30).ok
    spawn = hal.stub(SIM + "spawn_obstacle", rpc.RobonixPrimitiveSimSpawnObstacleStub)
    with pytest.raises(grpc.RpcError) as exc:
        spawn.SpawnObstacle(sim_pb2.SpawnObstacle_Request(name="bad", x=4.0, y=4.0, size_x=0.0, size_y=0.4),
                            timeout=30)
    assert exc.value.code() == grpc.StatusCode.INVALID_ARGUMENT
    assert "size_x" in exc.value.details()
    r = spawn.SpawnObstacle(sim_pb2.SpawnObstacle_Request(name="crate", x=4.0, y=4.0, size_x=0.4, size_y=0.4),
                            timeout=30)
    assert r.ok, r.detail
    t_spawn = gt(hal).sim_time
    wait_until(lambda: seen.get("/scan").header.stamp.to_sec() > t_spawn, 30, "a scan after the spawn")
    assert abs(float(seen.get("/scan").ranges[180]) - 1.3) < 0.02

    reset = hal.stub(SIM + "reset", rpc.RobonixPrimitiveSimResetStub)
    assert reset.ResetSim(sim_pb2.ResetSim_Request(), timeout=30).ok
    g = gt(hal)
    assert (round(g.x, 6), round(g.y, 6)) == (2.5, 4.0)
    assert g.sim_time >= t_spawn
    assert collisions.GetCollisions(sim_pb2.GetCollisions_Request(), timeout=30).count == 0
    info = hal.stub(SIM + "scene_info", rpc.RobonixPrimitiveSimSceneInfoStub).GetSceneInfo(
        sim_pb2.GetSceneInfo_Request(), timeout=30)
    assert "crate" not in [o["name"] for o in json.loads(info.info_json)["obstacles"]]

    # one MCP tool call through the atlas-declared MCP endpoint
    from mcp import Client

    with hal.client.connect_capability(consumer_id="hal_test", provider_id=hal.name, contract_id=SIM + "teleport",
                                       transport="mcp") as ch:
        url = ch.endpoint

    async def talk() -> Any:
        async with Client(url) as c:
            names = [t.name for t in (await c.list_tools()).tools]
            return names, await c.call_tool("teleport", {"x": 3.0, "y": 4.0, "theta": 0.0})

    names, result = asyncio.run(asyncio.wait_for(talk(), 60))
    assert {"ground_truth", "collisions", "teleport", "reset", "scene_info", "spawn_obstacle"} <= set(names)
    assert result.structured_content["ok"] is True
    assert abs(gt(hal).x - 3.0) < 1e-6


def test_deactivate_holds_then_reactivates(seen: Latest, hal: HalProcess, node: DdsNode) -> None:
    assert hal.deactivate() == (True, "inactive", "")
    wait_until(lambda: json.loads(hal.stub(SIM + "scene_info", rpc.RobonixPrimitiveSimSceneInfoStub)
                                  .GetSceneInfo(sim_pb2.GetSceneInfo_Request(), timeout=30).info_json)["mode"]
               == "held", 60, "the runner to hold")
    a = gt(hal)
    pub = node.create_publisher("/cmd_vel", Twist, "reliable")
    pub.wait_for_subscribers(1, 30)
    for _ in range(20):  # ignored while held
        pub.publish(twist(0.5, 0.0, 0.0))
        time.sleep(0.05)
    pub.close()
    # held republishes /odom: two more after the last command prove the HAL ran on, and still did not move
    n = seen.counts.get("/odom", 0)
    wait_until(lambda: seen.counts.get("/odom", 0) >= n + 2, 30, "two held /odom republished after the commands")
    b = gt(hal)
    assert b.sim_time == a.sim_time
    assert b.x == a.x
    assert hal.activate() == (True, "active", "")
    wait_until(lambda: gt(hal).sim_time > b.sim_time + 0.5, 60, "sim time to advance again")
