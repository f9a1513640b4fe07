"""Navigate → first non-zero /cmd_vel latency of the navigation provider, over real processes.

Starts an atlas (in-process), the HAL (MuJoCo, apartment, real time by default), the stand-in map
provider and ``python -m nav2_wrapper.atlas_bridge``; sends N goals over gRPC, each to the farther of
two rooms, and measures the wall time from sending Navigate to the first non-zero Twist seen on /cmd_vel
(includes the gRPC round trip, the wait for the next control tick and the first global plan). Each goal
is canceled once measured and the base left to stop. Prints the figure, writes
bench/results/nav_latency.json.

    python bench/nav_latency_bench.py [--goals 10] [--rtf 1.0]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import sys
import tempfile
import threading
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
os.environ.setdefault("ROS_DOMAIN_ID", str(10 + os.getpid() % 200))  # isolated, loopback-only DDS
os.environ.setdefault("CYCLONEDDS_URI", (REPO / "config" / "cyclonedds_loopback.xml").as_uri())

from atlas.server import AtlasServer  # noqa: E402
from robonix_api.dds import DdsNode, Twist  # noqa: E402
from robonix_api.proto_gen import navigation_pb2 as nav_pb  # noqa: E402
from robonix_api.proto_gen import robonix_contracts_pb2_grpc as rpc  # noqa: E402
from robonix_api.proto_gen import sim_pb2  # noqa: E402
from tests.support.procs import ACTIVATE, HAL, INIT, MAP_PROVIDER, NAV, Proc, wait_until  # noqa: E402

GOALS = [(7.0, 1.5), (3.5, 7.5)]  # kitchen, bedroom: each goal is sent from far away (the farther one)
OUT = REPO / "bench" / "results" / "nav_latency.json"


class FirstMotion:
    """Wall time of the first non-zero Twist on /cmd_vel after ``arm()``."""

    def __init__(self) -> None:
        self._ev = threading.Event()
        self._t = 0.0
        self._armed = False

    def arm(self) -> None:
        self._ev.clear()
        self._armed = True

    def on_twist(self, m: Twist) -> None:
        if self._armed and (m.linear.x or m.linear.y or m.angular.z):
            self._t = time.monotonic()
            self._armed = False
            self._ev.set()

    def wait(self, timeout_s: float) -> float | None:
        return self._t if self._ev.wait(timeout_s) else None


def goal(x: float, y: float) -> nav_pb.Navigate_Request:
    req = nav_pb.Navigate_Request()
    req.goal.header.frame_id = "map"
    req.goal.pose.position.x, req.goal.pose.position.y = x, y
    req.goal.pose.orientation.w = 1.0
    return req


def run(n: int, rtf: float, logs: Path) -> dict[str, object]:
    server = AtlasServer(listen="127.0.0.1:0")
    atlas = server.start()
    procs: list[Proc] = []
    node = DdsNode(name="nav_latency_bench")
    try:
        hal = Proc(HAL, atlas, "bench_hal", logs / "hal.log")
        procs.append(hal)
        mapper = Proc(MAP_PROVIDER, atlas, "bench_map", logs / "map.log")
        procs.append(mapper)
        nav = Proc(NAV, atlas, "bench_nav", logs / "nav.log")
        procs.append(nav)
        assert hal.driver(INIT, {"scene": "apartment", "real_time_factor": rtf})[0], hal.log()[-2000:]
        assert hal.driver(ACTIVATE)[0]
        assert mapper.driver(INIT, {"scene": "apartment"})[0]
        ok, _, err = nav.driver(INIT, {"params_profile": "sim", "use_sim_time": True, "action_wait_s": 90})
        assert ok, err
        assert nav.driver(ACTIVATE)[0]
        navigate = nav.stub("robonix/service/navigation/navigate", rpc.RobonixServiceNavigationNavigateStub)
        cancel = nav.stub("robonix/service/navigation/navigate/cancel", rpc.RobonixServiceNavigationNavigateCancelStub)
        gt = hal.stub("robonix/primitive/sim/ground_truth", rpc.RobonixPrimitiveSimGroundTruthStub)
        fm = FirstMotion()
        sub = node.create_subscription("/cmd_vel", Twist, fm.on_twist, "reliable")
        samples: list[float] = []
        for i in range(n):
            here = gt.GetGroundTruth(sim_pb2.GetGroundTruth_Request(), timeout=60)
            target = max(GOALS, key=lambda p: math.hypot(p[0] - here.x, p[1] - here.y))
            fm.arm()
            t0 = time.monotonic()
            r = navigate.Navigate(goal(*target), timeout=60)
            assert r.accepted, r.detail
            t1 = fm.wait(30)
            if t1 is None:
                st = nav.stub("robonix/service/navigation/navigate/status",
                              rpc.RobonixServiceNavigationNavigateStatusStub).GetNavigationStatus(
                    nav_pb.GetNavigationStatus_Request(run_id=r.run_id), timeout=60)
                raise RuntimeError(f"goal {i}: no motion command within 30 s ({st.state}: {st.detail})")
            samples.append((t1 - t0) * 1000.0)
            time.sleep(0.5 / max(rtf, 0.1))  # let it drive a little, then stop it
            cancel.CancelNavigation(nav_pb.CancelNavigation_Request(run_id=r.run_id), timeout=60)
            wait_until(lambda: math.hypot((g := gt.GetGroundTruth(sim_pb2.GetGroundTruth_Request(), timeout=60)).vx,
                                          g.vy) < 0.02, 60, "the base to stop", 0.05)
        sub.close()
    finally:
        node.close()
        for p in reversed(procs):
            p.stop()
        server.stop()
    s = sorted(samples)
    return {"figure": "navigate_to_first_nonzero_cmd_vel_ms", "goals": n, "median_ms": round(statistics.median(s), 1),
            "p95_ms": round(s[min(len(s) - 1, math.ceil(0.95 * len(s)) - 1)], 1), "min_ms": round(s[0], 1),
            "max_ms": round(s[-1], 1), "samples_ms": [round(v, 1) for v in samples], "real_time_factor": rtf,
            "controller_frequency_hz": 20.0, "scene": "apartment", "cpus": os.cpu_count()}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--goals", type=int, default=10)
    ap.add_argument("--rtf", type=float, default=1.0, help="HAL real_time_factor (sim time drives the loop)")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="nav_latency_") as tmp:
        res = run(a.goals, a.rtf, Path(tmp))
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(res, indent=2) + "\n")
    print(f"navigate -> first non-zero cmd_vel: median {res['median_ms']} ms, p95 {res['p95_ms']} ms "
          f"over {res['goals']} goals (rtf {res['real_time_factor']}); wrote {OUT.relative_to(REPO)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
