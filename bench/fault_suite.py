"""Fault suite: SIGKILL, and SIGSTOP for 5 s then SIGCONT, of each provider and of the atlas, while the
robot drives a goal in the sim deploy booted by ``rbnx boot`` (kitchen scene, real time).

Per case it measures, from the moment of the signal:
- robot stopped: sim seconds (and wall) until the simulator's ground-truth speed is < 0.05 m/s;
- status change: wall seconds until the goal's status reports it (paused "waiting for …", or a new state)
  and the reason it gives;
- recovery: wall seconds until every provider is ACTIVE on the atlas again (after a SIGKILL only if the
  entry runs under a new PID, i.e. something restarted it); "no restart" otherwise;
- whether the interrupted goal continued to SUCCEEDED, its final detail, whether a next goal succeeds;
- orphans: recorded processes still alive after ``rbnx shutdown``.

Ground truth (issue 37): after each goal's final status the simulator's true pose is read through the
sim-only contract; a SUCCEEDED farther than ``GOAL_TOL_M`` from the goal is a *false success* and the case
fails. ``--scene apartment`` drives far goals ((10, 7), then (7, 1.5)); ``--repeat N`` runs every case N
times; a mapping SIGKILL also compares the map saved just before the kill with the one saved once mapping
is ACTIVE again (occupied-cell IoU, must be >= 0.95: issue 33).

A killed atlas gets 5 s to be started again by the boot (``restart: on-failure``), else the suite starts
one at the same address (providers re-register by themselves). Prints a table and writes
bench/results/fault_suite.json.

    python bench/fault_suite.py [--cases mapping:stop atlas:kill ...] [--rtf 1] [--scene apartment] [--repeat 5]
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import signal
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tests"))
RESULTS = REPO / "bench" / "results" / "fault_suite.json"

from support.faults import KITCHEN, TERMINAL, Recorder, SimBoot, occupied_iou, signal_pid  # noqa: E402
from support.procs import wait_until  # noqa: E402

TARGETS = ("panda_mobile", "mapping", "nav2", "atlas")
KINDS = ("kill", "stop")
STOP_S = 5.0
STOP_WINDOW_S = 8.0  # wall s after the signal in which the robot must come to rest
GOAL, NEXT_GOAL = KITCHEN["pantry"], KITCHEN["island_east"]
#: far goals per scene: (interrupted goal, next goal)
SCENE_GOALS = {"kitchen": (GOAL, NEXT_GOAL), "apartment": ((10.0, 7.0), (7.0, 1.5))}
GOAL_TOL_M = 0.5  # a SUCCEEDED with the true robot farther than this from the goal is a false success
MIN_IOU = 0.95


def _fmt(v: float | None, unit: str = "s") -> str:
    return "-" if v is None or (isinstance(v, float) and math.isnan(v)) else f"{v:.2f} {unit}"


def _truth(boot: SimBoot, goal: tuple[float, float], state: str) -> dict[str, Any]:
    """The simulator's true pose after a goal's final status, and whether the status agrees with it."""
    try:
        gt = boot.ground_truth()
    except Exception as exc:
        return {"truth": f"ground truth not available: {_why(exc)}", "agrees": state != "SUCCEEDED"}
    d = math.hypot(gt.x - goal[0], gt.y - goal[1])
    return {"true_pose": [round(gt.x, 2), round(gt.y, 2)], "true_dist_m": round(d, 2),
            "agrees": state != "SUCCEEDED" or d <= GOAL_TOL_M}


def _save_map(boot: SimBoot, name: str, map_dir: Path) -> Any:
    """The live map saved as ``name`` (None when saving failed)."""
    from robonix_api.mapfile import load_map_yaml
    from robonix_api.proto_gen import map_pb2
    from robonix_api.proto_gen import robonix_contracts_pb2_grpc as stubs

    req = map_pb2.SaveMap_Request(map_id=name)
    r = boot._call("robonix/service/map/save_map",
                   lambda ch: stubs.RobonixServiceMapSaveMapStub(ch).SaveMap(req, timeout=60))
    return load_map_yaml(map_dir / name / "map.yaml") if r.ok else None


def run_case(target: str, kind: str, rtf: str, tmp: Path, scene: str = "kitchen") -> dict[str, Any]:
    fault = "SIGKILL" if kind == "kill" else f"SIGSTOP {STOP_S:g} s + SIGCONT"
    out: dict[str, Any] = {"target": target, "kind": kind, "fault": fault, "scene": scene}
    goal, next_goal = SCENE_GOALS[scene]
    map_dir = tmp / "maps"
    env = {"ROBONIX_MAPS_ROOT": str(map_dir), "ROBONIX_MAP_DIR": str(map_dir)}
    with SimBoot(tmp, scene=scene, rtf=rtf, env=env) as boot:
        run_id = boot.navigate(*goal)
        rec = Recorder(boot, run_id).start()
        before = None
        try:
            wait_until(rec.moving, 300, "the robot to drive the goal", 0.05)  # a cold numba cache: minutes
            time.sleep(1.0 if scene == "kitchen" else 8.0)  # well under way (far goals: mapped a good part)
            if target == "mapping" and kind == "kill":
                before = _save_map(boot, "before", map_dir)
            pid = boot.pids()[target]
            t0 = time.monotonic()
            signal_pid(pid, signal.SIGKILL if kind == "kill" else signal.SIGSTOP)
            if kind == "stop":
                time.sleep(STOP_S)
                signal_pid(pid, signal.SIGCONT)
            elif target == "atlas":
                out["atlas_restarted_by"] = boot.ensure_atlas(5.0)
            recovered = _wait_recovered(boot, target, kind, pid, t0)
            out["recovery_s"] = recovered
            if before is not None and recovered is not None:
                after = _save_map(boot, "after", map_dir)
                out["map_iou"] = round(occupied_iou(before, after), 3) if after is not None else None
            final = _wait_final(boot, run_id, 240 if scene != "kitchen" else 150)
            out["goal_final"], out["goal_detail"] = final
            out["goal_continued"] = final[0] == "SUCCEEDED"
            out["goal_truth"] = _truth(boot, goal, final[0])
        finally:
            rec.stop()
        if target == "panda_mobile":
            out["stopped"] = "sim frozen (the HAL is the simulator: no sim time passes, the robot cannot move)"
        elif target == "atlas":
            out["stopped"] = "not needed (the data plane is unaffected; the robot drives on)"
        else:
            stopped = rec.stopped_after(t0, within_s=STOP_WINDOW_S)
            out["stopped_sim_s"], out["stopped_wall_s"] = stopped if stopped else (None, None)
            out["stopped"] = f"{stopped[0]:.2f} s sim" if stopped else f"not within {STOP_WINDOW_S:g} s"
        change = rec.status_change_after(t0)
        if change and change[1] == "SUCCEEDED":
            out["status_change"] = "none: the goal went on and succeeded"
        elif change:
            out["status_change"] = f"{change[0]:.2f} s: {change[1]} '{change[2]}'"
            out["status_change_s"], out["status_state"], out["status_detail"] = change
        else:
            out["status_change"] = "none observed"
        try:
            nxt = boot.navigate(*next_goal)
            out["next_goal"] = boot.wait_terminal(nxt, 180)[0]
            out["next_truth"] = _truth(boot, next_goal, out["next_goal"])
        except Exception as exc:  # nav2 (or the sim) gone for good: say so
            out["next_goal"] = f"not possible: {_why(exc)}"
        out["orphans"] = boot.shutdown()
    out["ok"] = (out["goal_final"] == "SUCCEEDED" and out["next_goal"] == "SUCCEEDED"
                 and out["goal_truth"]["agrees"] and out.get("next_truth", {}).get("agrees", False)
                 and out.get("map_iou", 1.0) is not None and out.get("map_iou", 1.0) >= MIN_IOU)
    return out


def _wait_recovered(boot: SimBoot, target: str, kind: str, old_pid: int, t0: float,
                    timeout_s: float = 30.0) -> float | None:
    """Wall s until every provider is ACTIVE (after a SIGKILL: under a new PID); None = not in time."""
    deadline = t0 + timeout_s
    while time.monotonic() < deadline:
        replaced = kind != "kill" or boot.pids().get(target) not in (None, old_pid)
        if replaced and boot.all_active():
            return time.monotonic() - t0
        time.sleep(0.1)
    return None


def _why(exc: Exception) -> str:
    """One line for an error: a gRPC status as CODE: details, anything else its first line."""
    if hasattr(exc, "code") and hasattr(exc, "details"):
        try:
            return f"{exc.code().name}: {exc.details()}"[:160]
        except Exception:
            pass
    return (str(exc).splitlines() or [type(exc).__name__])[0][:160]


def _wait_final(boot: SimBoot, run_id: str, timeout_s: float, unreachable_s: float = 20.0) -> tuple[str, str]:
    """The goal's terminal (state, detail); gives up after ``unreachable_s`` without any status answer
    (navigation itself is gone)."""
    deadline = time.monotonic() + timeout_s
    last_ok, last = time.monotonic(), ("UNKNOWN", "")
    while time.monotonic() < deadline:
        try:
            last = boot.status(run_id)
            last_ok = time.monotonic()
            if last[0] in TERMINAL:
                return last
        except Exception as exc:
            if time.monotonic() - last_ok > unreachable_s:
                return "UNKNOWN", f"status not available: {_why(exc)}"
        time.sleep(0.25)
    return last


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cases", nargs="*", default=[f"{t}:{k}" for t in TARGETS for k in KINDS],
                    help=f"target:kind pairs (targets: {', '.join(TARGETS)}; kinds: kill, stop)")
    ap.add_argument("--rtf", default="1", help="simulator real-time factor (default 1)")
    ap.add_argument("--scene", choices=sorted(SCENE_GOALS), default="kitchen",
                    help="kitchen (short goals) or apartment (far goals (10, 7) then (7, 1.5))")
    ap.add_argument("--repeat", type=int, default=1, help="run every case this many times")
    ap.add_argument("--out", type=Path, default=RESULTS)
    args = ap.parse_args()
    if args.repeat < 1:
        print("fault_suite: --repeat: must be >= 1", file=sys.stderr)
        return 2
    cases = []
    for c in args.cases:
        t, _, k = c.partition(":")
        if t not in TARGETS or k not in KINDS:
            print(f"fault_suite: --cases: bad case {c!r} (target:kind with target in {', '.join(TARGETS)}, "
                  "kind kill|stop)", file=sys.stderr)
            return 2
        cases.append((t, k))
    results = []
    for t, k in [c for _ in range(args.repeat) for c in cases]:  # rounds: a cut-short run covers every case
        with tempfile.TemporaryDirectory(prefix=f"fault-{t}-{k}-") as d:
            t_case = time.monotonic()
            try:
                r = run_case(t, k, args.rtf, Path(d), args.scene)
            except Exception as exc:
                r = {"target": t, "kind": k, "fault": k, "error": f"{type(exc).__name__}: {str(exc)[:400]}",
                     "ok": False}
            r["case_s"] = round(time.monotonic() - t_case, 1)
            results.append(r)
            print(json.dumps(r), flush=True)
            _write(args, results)
    _table(results)
    for t, k in cases:
        rs = [r for r in results if r["target"] == t and r.get("kind") == k]
        false_ok = sum(1 for r in rs for key in ("goal_truth", "next_truth") if not r.get(key, {}).get("agrees", True))
        print(f"{t}:{k}: {sum(r.get('ok', False) for r in rs)}/{len(rs)} ok, {false_ok} false SUCCEEDED")
    print(f"wrote {args.out}")
    return 0


def _write(args: argparse.Namespace, results: list[dict[str, Any]]) -> None:
    """Results so far (rewritten after every case: a long run can be read while it goes on)."""
    goal, next_goal = SCENE_GOALS[args.scene]
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps({"machine": platform.node(), "rtf": args.rtf, "scene": args.scene,
                                    "when": time.strftime("%Y-%m-%d %H:%M:%S"),
                                    "stop_s": STOP_S, "goal": goal, "next_goal": next_goal, "cases": results},
                                   indent=2) + "\n")


def _table(results: list[dict[str, Any]]) -> None:
    head = ("target", "fault", "stopped (sim)", "status change", "recovery", "goal", "next", "orphans")
    rows = []
    for r in results:
        if "error" in r:
            rows.append((r["target"], r["fault"], "error: " + r["error"][:60], "", "", "", "", ""))
            continue
        stopped = r["stopped"].split(" (")[0]
        change = (f"{_fmt(r.get('status_change_s'))} {r.get('status_state', '')}" if "status_change_s" in r
                  and r.get("status_state") != "SUCCEEDED" else "none")
        rec = _fmt(r.get("recovery_s")) if r.get("recovery_s") is not None else "no restart"
        rows.append((r["target"], r["fault"], stopped, change, rec, r["goal_final"], str(r["next_goal"])[:12],
                     str(len(r["orphans"]))))
    widths = [max(len(str(x)) for x in col) for col in zip(head, *rows, strict=True)]
    for row in (head, *rows):
        print("  ".join(str(x).ljust(w) for x, w in zip(row, widths, strict=True)))
    for r in results:
        if "goal_detail" in r:
            print(f"- {r['target']} {r['fault']}: status '{r.get('status_detail', '')[:110]}' -> "
                  f"{r['goal_final']} '{r['goal_detail'][:110]}'")


if __name__ == "__main__":
    sys.exit(main())
