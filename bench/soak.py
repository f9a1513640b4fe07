"""All-day soak of the sim deploy: goals cycling through the scene's waypoints for hours of sim time.

Boots examples/sim/deploy.yaml through the real `rbnx boot` (atlas + MuJoCo HAL + SLAM + navigation),
sends goals through the same contracts `rbnx demo` uses, and every ``--sample-s`` wall seconds records
each recorded process's resident memory (/proc/PID/status VmRSS), the sim time, and the SLAM provider's
status (per-scan cost percentiles over its latest calls, node count, pruned nodes). Reports, per
process, the memory at 10 min of sim time vs at the end (growth %), the per-scan p99 per interval, and
goals succeeded / failed. Acceptance (issue 20): mapping memory after 10 min grows <= 10 %, p99 flat,
every goal succeeds.

    python bench/soak.py [--sim-hours 2] [--rtf 3] [--sample-s 30] [--scene apartment]

Writes bench/results/soak.json (also after Ctrl-C, with what ran). Every process is stopped through the
boot (SIGINT, then by recorded PID), never by name.
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import platform
import signal
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

from rbnx.demo.boot import BootChild, DemoError, pick_domain_id
from rbnx.demo.goals import TERMINAL, choose_goals
from rbnx.demo.rpc import DemoRpc
from robonix_api.proto_gen import map_pb2
from robonix_api.proto_gen import robonix_contracts_pb2_grpc as stubs
from robonix_nav_data import resources

REPO = Path(__file__).resolve().parents[1]
RESULTS = REPO / "bench" / "results" / "soak.json"
GET_MODE = "robonix/service/map/get_mode"
SETTLE_SIM_S = 600.0  # memory is compared from this sim time on: the first minutes map the scene
MIN_GOAL_DIST_M = 1.0


def rss_mb(pid: int) -> float | None:
    """Resident set size of ``pid`` in MB, None when it is gone."""
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    except OSError:
        return None
    return None


class Sampler:
    """Background sampling of memory, sim time and SLAM status (its own RPC client: thread-safe use)."""

    def __init__(self, boot: BootChild, atlas: str, period_s: float) -> None:
        self.boot, self.period = boot, period_s
        self.rpc = DemoRpc(atlas)
        self.samples: list[dict[str, Any]] = []
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, name="soak-sampler", daemon=True)

    def slam_status(self) -> dict[str, Any]:
        r = self.rpc._call(GET_MODE, stubs.RobonixServiceMapGetModeStub, "GetMode", map_pb2.GetMode_Request())
        return json.loads(r.detail) if r.ok else {}

    def sample(self) -> dict[str, Any]:
        s: dict[str, Any] = {"wall_s": round(time.monotonic(), 1), "rss_mb": {}}
        for name, pid, _ticks in self.boot.recorded():
            mb = rss_mb(pid)
            if mb is not None:  # a package with helper processes: summed under its name
                s["rss_mb"][name] = round(s["rss_mb"].get(name, 0.0) + mb, 1)
        try:
            s["sim_time"] = round(self.rpc.ground_truth().sim_time, 1)
            st = self.slam_status()
            eng = st.get("engine", {})
            s["slam"] = {k: st.get(k) for k in ("process_ms_p50", "process_ms_p99", "process_ms_max",
                                                "process_cpu_ms_p99", "nodes", "process_over_100ms",
                                                "scans_dropped_behind", "autosaves")}
            s["slam"].update({k: eng.get(k) for k in ("nodes_pruned", "loop_closures", "scans_integrated")})
        except DemoError as exc:
            s["error"] = str(exc)
        return s

    def _run(self) -> None:
        while not self.stop.is_set():
            self.samples.append(self.sample())
            last = self.samples[-1]
            print(f"[soak] sim {last.get('sim_time', '?')} s  rss {last['rss_mb']}  slam {last.get('slam')}",
                  flush=True)
            self.stop.wait(self.period)

    def close(self) -> None:
        self.stop.set()
        self.thread.join(30)
        self.rpc.close()


def run_goal(rpc: DemoRpc, goal: Any, timeout_s: float, stop: threading.Event) -> dict[str, Any]:
    t0 = time.monotonic()
    accepted, run_id, detail = rpc.navigate(goal)
    state = "REJECTED"
    if accepted:
        state = "PENDING"
        while not stop.is_set():
            if time.monotonic() - t0 > timeout_s:
                rpc.cancel(run_id)
                state, detail = "TIMEOUT", f"no result after {timeout_s:g} s wall"
                break
            try:
                st = rpc.status(run_id)
                state, detail = st.state, st.detail
            except DemoError as exc:
                detail = str(exc)
            if state in TERMINAL:
                break
            stop.wait(0.5)
        else:
            rpc.cancel(run_id)
            state = "CANCELED"
    return {"name": goal.name, "x": goal.x, "y": goal.y, "state": state, "detail": detail[:200],
            "wall_s": round(time.monotonic() - t0, 1)}


def summarize(samples: list[dict[str, Any]], goals: list[dict[str, Any]], args: argparse.Namespace
              ) -> dict[str, Any]:
    ok = [s for s in samples if "sim_time" in s]
    out: dict[str, Any] = {"sim_hours_target": args.sim_hours, "rtf": args.rtf, "scene": args.scene,
                           "sim_hours_reached": round(ok[-1]["sim_time"] / 3600.0, 3) if ok else 0.0,
                           "goals_sent": len(goals), "goals_succeeded": sum(g["state"] == "SUCCEEDED" for g in goals),
                           "goals_failed": [g for g in goals if g["state"] != "SUCCEEDED"]}
    settled = [s for s in ok if s["sim_time"] >= SETTLE_SIM_S]
    growth: dict[str, Any] = {}
    if settled and ok:
        first, last = settled[0], ok[-1]
        for name, mb in first["rss_mb"].items():
            end = last["rss_mb"].get(name)
            if end is not None:
                growth[name] = {"at_10min_mb": mb, "end_mb": end, "growth_pct": round(100.0 * (end - mb) / mb, 1),
                                "max_mb": max(s["rss_mb"].get(name, 0.0) for s in settled)}
    out["memory_after_10min"] = growth or "not reached (sim time < 10 min)"
    out["slam_p99_ms_per_interval"] = [(s["sim_time"], s.get("slam", {}).get("process_ms_p99")) for s in ok]
    # CPU time of the same calls: the wall p99 follows whatever else the host runs, this one does not
    out["slam_cpu_p99_ms_per_interval"] = [(s["sim_time"], s.get("slam", {}).get("process_cpu_ms_p99")) for s in ok]
    out["slam_nodes_per_interval"] = [(s["sim_time"], s.get("slam", {}).get("nodes")) for s in ok]
    m = growth.get("mapping")
    out["acceptance"] = {
        "mapping_growth_le_10pct": None if m is None else m["growth_pct"] <= 10.0,
        "all_goals_succeeded": bool(goals) and not out["goals_failed"],
        "sim_hours_reached_target": out["sim_hours_reached"] >= args.sim_hours,
    }
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sim-hours", type=float, default=2.0)
    ap.add_argument("--rtf", type=float, default=3.0, help="sim real-time factor (3 is sustained on 2 cores)")
    ap.add_argument("--sample-s", type=float, default=30.0, help="wall s between samples")
    ap.add_argument("--scene", default="apartment")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--goal-timeout-s", type=float, default=300.0, help="wall s per goal")
    args = ap.parse_args()
    work = Path(tempfile.mkdtemp(prefix="rbnx-soak-"))
    env = dict(os.environ, RBNX_SIM_SCENE=args.scene, RBNX_SIM_RTF=f"{args.rtf:g}", PYTHONUNBUFFERED="1",
               RBNX_STATE_DIR=str(work / "state"), RBNX_ATLAS_LISTEN="127.0.0.1:0")
    env.pop("ROBONIX_ATLAS", None)
    env.setdefault("ROS_DOMAIN_ID", str(pick_domain_id()))
    boot = BootChild(resources.example_deploy("sim"), work, env, boot_timeout=180.0)
    stop = threading.Event()

    def on_signal(signum: int, _frame: Any) -> None:
        print(f"\n{signal.Signals(signum).name}: stopping the soak", file=sys.stderr, flush=True)
        stop.set()

    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, on_signal)
    goals: list[dict[str, Any]] = []
    sampler: Sampler | None = None
    result: dict[str, Any] = {"when": time.strftime("%Y-%m-%dT%H:%M:%S"), "logs": str(boot.log_dir),
                              "host": {"python": platform.python_version(), "cpus": os.cpu_count(),
                                       "load_avg_at_start": os.getloadavg()[0]}}
    rpc: DemoRpc | None = None
    try:
        boot.start()
        atlas = boot.wait_active(["panda_mobile", "mapping", "nav2"], 240.0, stop)
        print(f"[soak] system up, atlas {atlas}; logs {boot.log_dir}", flush=True)
        rpc = DemoRpc(atlas)
        sampler = Sampler(boot, atlas, args.sample_s)
        sampler.thread.start()
        info = rpc.scene_info()
        gt = rpc.ground_truth()
        pool = choose_goals(info.get("waypoints") or {}, (gt.x, gt.y), 64, args.seed, MIN_GOAL_DIST_M)
        if not pool:
            raise DemoError(f"scene {args.scene!r} has no usable waypoint")
        for goal in itertools.cycle(pool):
            if stop.is_set() or not boot.running():
                break
            if rpc.ground_truth().sim_time >= args.sim_hours * 3600.0:
                break
            g = run_goal(rpc, goal, args.goal_timeout_s, stop)
            goals.append(g)
            print(f"[soak] goal {len(goals)} {g['name']}: {g['state']} ({g['wall_s']} s wall)", flush=True)
    except (DemoError, KeyboardInterrupt) as exc:
        result["error"] = str(exc)
        print(f"[soak] error: {exc}", file=sys.stderr, flush=True)
    finally:
        if sampler is not None:
            sampler.close()
            if boot.running():  # the state at the end, not up to one period before it
                sampler.samples.append(sampler.sample())
        if rpc is not None:
            rpc.close()
        leftovers = boot.stop()
        result["leftover_processes"] = leftovers
        samples = sampler.samples if sampler is not None else []
        result.update(summarize(samples, goals, args))
        result["samples"], result["goals"] = samples, goals
        RESULTS.parent.mkdir(parents=True, exist_ok=True)
        RESULTS.write_text(json.dumps(result, indent=2) + "\n")
        brief = {k: result[k] for k in ("sim_hours_reached", "goals_sent", "goals_succeeded", "memory_after_10min",
                                        "acceptance")}
        print(json.dumps(brief, indent=2))
        print(f"-> {RESULTS.relative_to(REPO)}")
    return 0 if result.get("acceptance", {}).get("all_goals_succeeded") else 1


if __name__ == "__main__":
    sys.exit(main())
