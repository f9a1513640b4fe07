"""nav2_wrapper.inputs.Inputs.lost() over real DDS: a stopped map→odom writer is a lost *required* input
named by its provider, a killed lidar an *optional* one (degrade), and both come back when they do."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest
from support.wait import wait_until

from nav2_wrapper.config import Frames
from nav2_wrapper.inputs import Inputs
from nav2_wrapper.upstream import MAP, ODOM, SCAN
from robonix_api.dds import DdsNode
from robonix_api.upstream import Binding

# map provider + chassis stand-in: /lv_map (latched), /lv_odom, TF map→odom (from a second node: its own
# writer, as SLAM's is) and odom→base_link, wall-clock stamps (use_sim_time false)
BASE = r"""
import sys, time
import numpy as np
from robonix_api.dds import DdsNode, Odometry, OccupancyGrid, TfBroadcaster, LaserScan
from robonix_api.dds.convert import grid_to_msg, laser_scan
from robonix_common.grid import GridMap
role = sys.argv[1]
node = DdsNode(name=role)
if role == "base":
    m = node.create_publisher("/lv_map", OccupancyGrid, "latched")
    m.publish(grid_to_msg(GridMap(np.zeros((40, 40), dtype=np.int8), 0.05, -1.0, -1.0, 0.0), time.time()))
    odom = node.create_publisher("/lv_odom", Odometry, "reliable")
    tf = TfBroadcaster(node)
elif role == "slam_tf":
    tf = TfBroadcaster(node)
else:
    scan = node.create_publisher("/lv_scan", LaserScan, "best_effort")
print("READY", flush=True)
while True:
    t = time.time()
    if role == "base":
        odom.publish(Odometry())
        tf.send("odom", "base_link", 0.0, 0.0, 0.0, t)
    elif role == "slam_tf":
        tf.send("map", "odom", 0.0, 0.0, 0.0, t)
    else:
        scan.publish(laser_scan(np.ones(36), -3.14, 0.17, range_max=5.0, stamp=t, frame_id="laser"))
    time.sleep(0.05)
"""


def _start(role: str) -> subprocess.Popen:
    p = subprocess.Popen([sys.executable, "-c", BASE, role], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    line = p.stdout.readline()
    if line.strip() != "READY":
        p.kill()
        pytest.fail(f"{role} did not start: {line!r} {p.stderr.read()[-2000:]}")
    return p


def test_inputs_lost_names_the_stopped_map_provider_and_degrades_on_scan() -> None:
    procs = {r: _start(r) for r in ("base", "slam_tf", "lidar")}
    node = DdsNode(name="inputs-test")
    bindings = {"map": Binding("map", "/lv_map", "latched", "mapping", MAP),
                "odom": Binding("odom", "/lv_odom", "reliable", "panda_mobile", ODOM),
                "scan": Binding("scan", "/lv_scan", "best_effort", "lidar_box", SCAN)}
    inputs = Inputs(node, bindings, Frames(), use_sim_time=False)

    def lost() -> tuple[dict[str, str], dict[str, str]]:
        now = time.time()
        try:
            state = inputs.robot_state(now)
        except Exception:
            state = None
        return inputs.lost(now, state, data_timeout_s=1.0, map_tf_timeout_s=10.0)

    try:
        wait_until(lambda: not inputs.missing() and lost() == ({}, {}), 15.0,
                   lambda: f"every input: {inputs.missing()} {lost()}")
        os.kill(procs["slam_tf"].pid, signal.SIGSTOP)
        wait_until(lambda: "mapping" in lost()[0], 15.0, lambda: f"mapping lost: {lost()}")
        req, opt = lost()
        assert req == {"mapping": "TF map→odom stopped (DDS liveliness lost)"}
        assert opt == {}
        os.kill(procs["slam_tf"].pid, signal.SIGCONT)
        wait_until(lambda: lost() == ({}, {}), 15.0, lambda: f"nothing lost: {lost()}")

        procs["lidar"].kill()
        wait_until(lambda: lost()[1] != {}, 15.0, lambda: f"an optional input lost: {lost()}")
        assert lost() == ({}, {"lidar_box": "/lv_scan stopped (DDS liveliness lost)"})

        procs["base"].kill()
        wait_until(lambda: "panda_mobile" in lost()[0], 15.0, lambda: f"panda_mobile lost: {lost()}")
        assert lost()[0]["panda_mobile"] == "/lv_odom stopped (DDS liveliness lost)"
        inputs.set_terminated("map", "the atlas reports mapping TERMINATED")
        assert lost()[0]["mapping"] == "the atlas reports mapping TERMINATED"
    finally:
        for p in procs.values():
            if p.poll() is None:
                os.kill(p.pid, signal.SIGCONT)
                p.kill()
            p.wait(10)
        inputs.close()
        node.close()
