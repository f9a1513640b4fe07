"""Simulator core benchmark: real-time factor and time per scan, headless.

Workload per run: physics at 500 Hz, a 360-beam scan at 10 Hz, odometry read at 50 Hz (integrated
internally at 50 Hz), a fresh /cmd_vel at 10 Hz. Core only: DDS publishing is added with the provider
later and is not included here. Goal: RTF >= 50x.

    python bench/sim_bench.py [--scene apartment] [--seconds 60] [--repeats 3]

Prints the figures and writes bench/results/sim.json.
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import statistics
import time
from pathlib import Path

import mujoco
import numpy as np

from hal_panda_mobile.files import load_robot_description, load_scene
from hal_panda_mobile.sim import PandaMobileSim
from hal_panda_mobile.sim.lidar import VISIBLE_GROUPS

RESULTS = Path(__file__).resolve().parent / "results" / "sim.json"


def run_workload(sim: PandaMobileSim, seconds: float) -> tuple[float, list[float]]:
    """Returns (wall seconds, per-scan wall seconds)."""
    odom_steps = round(0.02 / sim.timestep)  # 50 Hz
    ticks = round(seconds / 0.02)
    scan_times: list[float] = []
    t0 = time.perf_counter()
    for i in range(ticks):
        if i % 5 == 0:  # 10 Hz: command + scan
            t = sim.time
            sim.set_cmd_vel(0.4, 0.1 * math.sin(0.5 * t), 0.8 * math.sin(0.3 * t))
            s0 = time.perf_counter()
            sim.scan()
            scan_times.append(time.perf_counter() - s0)
        sim.step(odom_steps)
        sim.odometry()
    return time.perf_counter() - t0, scan_times


def multiray_only(sim: PandaMobileSim, n: int = 2000) -> float:
    """Median seconds of the bare mj_multiRay call for the same 360 beams (the floor for scan())."""
    m, d = sim.model, sim.data
    mujoco.mj_kinematics(m, d)
    beams = sim.robot.lidar.beams
    a = np.linspace(-math.pi, math.pi, beams, endpoint=False)
    vec = np.stack([np.cos(a), np.sin(a), np.zeros(beams)], axis=1).ravel()
    gid, dist = np.empty(beams, np.int32), np.empty(beams)
    pnt = d.site_xpos[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, "lidar")].copy()
    body = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "base")
    out = []
    for _ in range(n):
        t = time.perf_counter()
        mujoco.mj_multiRay(m, d, pnt, vec, VISIBLE_GROUPS, 1, body, gid, dist, None, beams, 12.0)
        out.append(time.perf_counter() - t)
    return statistics.median(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="apartment")
    ap.add_argument("--seconds", type=float, default=60.0, help="sim seconds per run")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()

    robot = load_robot_description()
    scene = load_scene(args.scene, robot=robot)
    rtfs, scan_all = [], []
    for r in range(args.repeats):
        sim = PandaMobileSim(robot, scene, seed=r)
        wall, scans = run_workload(sim, args.seconds)
        rtfs.append(sim.time / wall)
        scan_all += scans
        print(f"run {r}: {sim.time:.1f} sim s in {wall:.3f} wall s -> RTF {rtfs[-1]:.1f}x, "
              f"{len(sim.collisions())} collisions")
    sim = PandaMobileSim(robot, scene)
    t = time.perf_counter()
    sim.step(round(args.seconds / sim.timestep))
    physics_rtf = args.seconds / (time.perf_counter() - t)
    mr = multiray_only(sim)
    res = {
        "bench": "sim_core",
        "scene": args.scene,
        "obstacle_geoms": len(scene.obstacles()),
        "physics_hz": 1.0 / sim.timestep,
        "scan_hz": 10.0,
        "odom_hz": 50.0,
        "beams": robot.lidar.beams,
        "sim_seconds_per_run": args.seconds,
        "rtf_median": statistics.median(rtfs),
        "rtf_runs": rtfs,
        "rtf_goal": 50.0,
        "physics_only_rtf": physics_rtf,
        "scan_ms_median": 1e3 * statistics.median(scan_all),
        "scan_ms_p95": 1e3 * float(np.percentile(scan_all, 95)),
        "multiray_only_ms_median": 1e3 * mr,
        "note": "core only (no DDS publishing yet); machine shared with other jobs",
        "machine": platform.processor() or platform.machine(),
        "mujoco": mujoco.__version__,
    }
    print(f"RTF median {res['rtf_median']:.1f}x (goal >= 50x); physics only {physics_rtf:.0f}x")
    print(f"scan() median {res['scan_ms_median']:.3f} ms (p95 {res['scan_ms_p95']:.3f} ms); "
          f"bare mj_multiRay {res['multiray_only_ms_median']:.3f} ms")
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(json.dumps(res, indent=2) + "\n")
    print(f"wrote {RESULTS}")


if __name__ == "__main__":
    main()
