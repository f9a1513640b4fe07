"""Achieved real-time factor of the hal_panda_mobile sim loop *with* DDS publishing.

One command: ``python bench/hal_provider_bench.py`` (prints the figure, writes
bench/results/hal_provider.json). It runs the provider's own loop (``SimLoop`` + ``Outputs``, the code
``python -m hal_panda_mobile`` runs after CMD_INIT) at real_time_factor 0 with physics 500 Hz, 10 Hz
360-beam /scan, 50 Hz /odom + TF, 100 Hz /clock and 10 Hz ground truth (the provider's defaults), for a fixed
wall time while the base drives circles. A subscriber in a separate process receives /scan and /odom, so the writers
really serialize and deliver (matched reliable readers), and confirms the message counts. The atlas is
left out: it is not on the loop's path. Own ROS_DOMAIN_ID, loopback-only Cyclone config.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
RESULTS = REPO / "bench" / "results" / "hal_provider.json"


def sink(seconds: float) -> None:
    """Child process: count /scan and /odom deliveries until stdin closes, print them as JSON."""
    from robonix_api.dds import DdsNode, LaserScan, Odometry

    counts = {"scan": 0, "odom": 0}

    def bump(key: str):
        def cb(_msg: object) -> None:
            counts[key] += 1
        return cb

    with DdsNode(name="bench_sink") as node:
        node.create_subscription("/scan", LaserScan, bump("scan"), "best_effort")
        node.create_subscription("/odom", Odometry, bump("odom"), "reliable")
        print("ready", flush=True)
        sys.stdin.read()
        time.sleep(0.5)
    print(json.dumps(counts), flush=True)


#: The issue's figure (physics + scan + odom publishing) and the provider's full default output set.
WORKLOADS = {
    "issue": {"rates": dict(odom=50.0, scan=10.0, clock=None, ground_truth=None), "clock": False,
              "setup": "physics 500 Hz, scan 10 Hz x 360 beams, odom+TF 50 Hz"},
    "defaults": {"rates": dict(odom=50.0, scan=10.0, clock=100.0, ground_truth=10.0), "clock": True,
                 "setup": "physics 500 Hz, scan 10 Hz x 360 beams, odom+TF 50 Hz, clock 100 Hz, ground truth 10 Hz"},
}


def run(seconds: float, workload: str) -> dict:
    from hal_panda_mobile.config import build_sim, parse_config
    from hal_panda_mobile.loop import LoopRates, SimLoop
    from hal_panda_mobile.outputs import FrameNames, Outputs
    from robonix_api.dds import DdsNode, LaserScan, Odometry

    child = subprocess.Popen([sys.executable, __file__, "--sink"], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                             text=True, env=os.environ.copy())
    try:
        assert child.stdout is not None
        assert child.stdin is not None
        assert child.stdout.readline().strip() == "ready"
        cfg = parse_config({"scene": "warehouse", "real_time_factor": 0})
        sim = build_sim(cfg)
        node = DdsNode(name="bench_hal")
        outputs = Outputs(node, FrameNames("odom", "base_link", "laser", "world"),
                          odom_pub=node.create_publisher("/odom", Odometry, "reliable"),
                          scan_pub=node.create_publisher("/scan", LaserScan, "best_effort"),
                          gt_pub=node.create_publisher("/ground_truth/odom", Odometry, "reliable"),
                          publish_clock=WORKLOADS[workload]["clock"], scan_period=0.1, noisy_odom=False)
        runner = SimLoop(sim, outputs, LoopRates(**WORKLOADS[workload]["rates"]), real_time_factor=0.0)
        outputs.publish_static(sim.robot.lidar.mount, 0.0)
        time.sleep(1.0)  # discovery: the sink's readers match before the clock starts
        runner.start()
        runner.activate()
        t0 = time.monotonic()
        while time.monotonic() - t0 < seconds:  # keep the base moving (cmd_vel times out after 0.5 s sim)
            runner.cmd_vel(0.3, 0.0, 0.4)
            time.sleep(0.005)
        runner.stop()
        wall = time.monotonic() - t0
        sim_s = sim.time
        counts = dict(outputs.counts)
        outputs.close()
        node.close()
        child.stdin.close()
        received = json.loads(child.stdout.readline())
    finally:
        if child.poll() is None:
            child.wait(30)
    return {
        "real_time_factor": round(sim_s / wall, 1),
        "loop_achieved_rtf": round(runner.stats.achieved_rtf, 1),
        "wall_s": round(wall, 2),
        "sim_s": round(sim_s, 2),
        "published": counts,
        "received": received,
        "loop_errors": runner.stats.errors,
        "workload": workload,
        "setup": WORKLOADS[workload]["setup"] + ", rtf 0, scene warehouse, subscriber process on /scan and /odom",
        "host": {"python": platform.python_version(), "machine": platform.machine(), "cpus": os.cpu_count()},
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seconds", type=float, default=10.0, help="wall seconds to run (default 10)")
    ap.add_argument("--sink", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    os.environ.setdefault("ROS_DOMAIN_ID", str(10 + os.getpid() % 200))  # the sink inherits the parent's
    os.environ.setdefault("CYCLONEDDS_URI", (REPO / "config" / "cyclonedds_loopback.xml").as_uri())
    if args.sink:
        sink(args.seconds)
        return 0
    results = {}
    for workload in WORKLOADS:
        result = results[workload] = run(args.seconds, workload)
        print(f"[{workload}] {result['setup']}: real-time factor {result['real_time_factor']}x "
              f"({result['sim_s']} s sim in {result['wall_s']} s wall)")
        print(f"    published {result['published']}, received by subscriber {result['received']}, "
              f"loop errors {result['loop_errors']}")
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(json.dumps(results, indent=2) + "\n")
    print(f"wrote {RESULTS.relative_to(REPO)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
