"""Boot-to-ACTIVE time through the real `rbnx boot`: the shipped sim deploy, cold and warm, and a
4-provider dummy deploy.

- sim (examples/sim/deploy.yaml: atlas + MuJoCo HAL + SLAM + navigation), goals warm ≤ 3 s, cold ≤ 6 s.
  Cold = the first boot after install: an empty user cache dir (XDG_CACHE_HOME), so numba has to
  compile the planner kernels into it; warm = the next boots with that cache.
- dummy: two consumers listed before the two primitives they need (Deferred retries), goal ≤ 5 s.

Prints the medians and writes bench/results/boot.json.

    python bench/boot_bench.py [--runs 3] [--only sim|dummy]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import shutil
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from robonix_nav_data import resources

REPO = Path(__file__).resolve().parents[1]
MINIMAL = resources.examples_dir() / "minimal"
SIM_DEPLOY = resources.example_deploy("sim")
RESULTS = REPO / "bench" / "results" / "boot.json"
READY = re.compile(r"boot: (\d+)/(\d+) entries ready in ([0-9.]+)s")
ENTRY = re.compile(r"^  (\S+)\s+\S+\s+active\s+([0-9.]+)s", re.M)

DEPLOY = f"""manifestVersion: 1
name: boot-bench
system: {{atlas: {{listen: "127.0.0.1:0"}}}}
service:
  - {{name: consumer_a, path: {MINIMAL}/odom_consumer, config: {{provider_ids: {{odom: odom_a}}}}}}
  - {{name: consumer_b, path: {MINIMAL}/odom_consumer, config: {{provider_ids: {{odom: odom_b}}}}}}
primitive:
  - {{name: odom_a, path: {MINIMAL}/odom_primitive, config: {{topic: /odom_a}}}}
  - {{name: odom_b, path: {MINIMAL}/odom_primitive, config: {{topic: /odom_b}}}}
"""


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def rbnx() -> list[str]:
    exe = Path(sys.executable).parent / "rbnx"
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "rbnx.cli"]


def one_run(work: Path, i: int, deploy: Path, **env_extra: str) -> dict[str, Any]:
    """Boot, read the summary, SIGINT, time the shutdown."""
    out = work / f"run{i}.out"
    env = dict(os.environ, RBNX_STATE_DIR=str(work / "state"), PYTHONUNBUFFERED="1", **env_extra)
    t0 = time.monotonic()
    with open(out, "w") as fh:
        proc = subprocess.Popen(rbnx() + ["boot", "-f", str(deploy), "--no-progress",
                                          "--log-dir", str(work / f"logs{i}"), "--term-timeout", "10"],
                                env=env, stdout=fh, stderr=subprocess.STDOUT)
    try:
        deadline = t0 + 180
        m = None
        while m is None:
            m = READY.search(out.read_text())
            if proc.poll() is not None and m is None:
                raise RuntimeError(f"rbnx boot exited {proc.returncode}:\n{out.read_text()}")
            if time.monotonic() > deadline:
                raise RuntimeError(f"no summary within 180 s:\n{out.read_text()}")
            time.sleep(0.02)
        wall = time.monotonic() - t0
        ready, total, boot_s = int(m.group(1)), int(m.group(2)), float(m.group(3))
        if ready != total:
            raise RuntimeError(f"only {ready}/{total} ready:\n{out.read_text()}")
        t1 = time.monotonic()
        proc.send_signal(signal.SIGINT)
        proc.wait(120)
        text = out.read_text()
        return {"wall_s": wall, "rbnx_reported_s": boot_s, "shutdown_s": time.monotonic() - t1,
                "deferred_seen": float("deferred(" in text),
                "entry_active_s": {name: float(t) for name, t in ENTRY.findall(text)}}
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def _median(runs: list[dict[str, Any]], key: str) -> float:
    return round(statistics.median(r[key] for r in runs), 3)


def bench_dummy(work: Path, runs: int) -> dict[str, Any]:
    (work / "deploy.yaml").write_text(DEPLOY)
    out = []
    for i in range(runs):
        r = one_run(work, i, work / "deploy.yaml")
        out.append(r)
        print(f"dummy run {i + 1}/{runs}: ACTIVE after {r['wall_s']:.2f}s wall "
              f"({r['rbnx_reported_s']:.2f}s after validation), shutdown {r['shutdown_s']:.2f}s", flush=True)
    med = _median(out, "wall_s")
    print(f"dummy boot-to-ACTIVE (4 providers): median {med:.2f}s wall, {_median(out, 'rbnx_reported_s'):.2f}s "
          f"reported by rbnx; shutdown median {_median(out, 'shutdown_s'):.2f}s; goal ≤ 5 s "
          f"{'met' if med <= 5.0 else 'NOT met'}", flush=True)
    return {"benchmark": "boot-to-ACTIVE, 4 providers (2 consumers listed before 2 primitives; Deferred retried)",
            "median_boot_to_active_wall_s": med, "median_boot_reported_s": _median(out, "rbnx_reported_s"),
            "median_shutdown_s": _median(out, "shutdown_s"), "goal_s": 5.0, "goal_met": med <= 5.0,
            "all_runs": out}


def bench_sim(work: Path, runs: int) -> dict[str, Any]:
    """Cold: each run with a fresh cache dir; warm: runs sharing one cache dir (after a priming boot)."""
    domain = str(100 + os.getpid() % 100)
    cold, warm = [], []
    for i in range(runs):
        # A fixed port like the deploy's default (127.0.0.1:50051), but a free one: with the address known
        # in advance rbnx starts the packages while the atlas comes up.
        env = {"RBNX_ATLAS_LISTEN": f"127.0.0.1:{free_port()}", "ROS_DOMAIN_ID": domain}
        r = one_run(work, i, SIM_DEPLOY, XDG_CACHE_HOME=str(work / f"cold-cache{i}"), **env)
        cold.append(r)
        print(f"sim cold run {i + 1}/{runs}: all ACTIVE after {r['wall_s']:.2f}s wall "
              f"({r['rbnx_reported_s']:.2f}s by rbnx) {r['entry_active_s']}", flush=True)
    warm_cache = str(work / "cold-cache0")  # primed by the first cold run
    for i in range(runs):
        env = {"RBNX_ATLAS_LISTEN": f"127.0.0.1:{free_port()}", "ROS_DOMAIN_ID": domain}
        r = one_run(work, 100 + i, SIM_DEPLOY, XDG_CACHE_HOME=warm_cache, **env)
        warm.append(r)
        print(f"sim warm run {i + 1}/{runs}: all ACTIVE after {r['wall_s']:.2f}s wall "
              f"({r['rbnx_reported_s']:.2f}s by rbnx) {r['entry_active_s']}", flush=True)
    res = {"benchmark": "boot-to-ACTIVE of examples/sim/deploy.yaml (atlas + MuJoCo HAL + SLAM + nav2)",
           "cold_median_wall_s": _median(cold, "wall_s"), "warm_median_wall_s": _median(warm, "wall_s"),
           "cold_median_reported_s": _median(cold, "rbnx_reported_s"),
           "warm_median_reported_s": _median(warm, "rbnx_reported_s"),
           "goal_s": {"warm": 3.0, "cold": 6.0}, "cold_runs": cold, "warm_runs": warm}
    res["goal_met"] = res["warm_median_wall_s"] <= 3.0 and res["cold_median_wall_s"] <= 6.0
    print(f"sim boot-to-ACTIVE: cold median {res['cold_median_wall_s']:.2f}s (goal ≤ 6), warm median "
          f"{res['warm_median_wall_s']:.2f}s (goal ≤ 3) wall; {'met' if res['goal_met'] else 'NOT met'}",
          flush=True)
    return res


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--only", choices=("sim", "dummy"))
    args = ap.parse_args()
    work = Path(tempfile.mkdtemp(prefix="rbnx-boot-bench-"))
    result: dict[str, Any] = {"runs": args.runs, "when": time.strftime("%Y-%m-%dT%H:%M:%S"),
                              "host": {"python": platform.python_version(), "cpus": os.cpu_count(),
                                       "machine": platform.machine(),
                                       "load_avg_at_start": os.getloadavg()[0]}}
    try:
        if args.only in (None, "sim"):
            result["sim"] = bench_sim(work, args.runs)
        if args.only in (None, "dummy"):
            result["dummy"] = bench_dummy(work, args.runs)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(json.dumps(result, indent=2) + "\n")
    print(f"-> {RESULTS.relative_to(REPO)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
