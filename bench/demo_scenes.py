"""The whole multi-process system over many scenes: ``rbnx demo`` once per scene, one after the other.

One command: ``python bench/demo_scenes.py`` (prints a table, writes bench/results/demo_scenes.json).
Default list: the four built-in scenes with ``--goals 10`` and the generated scenes ``random:1`` …
``random:20`` with ``--goals 5``. Each demo boots atlas + simulator + SLAM + navigation as separate
processes, drives its goals and shuts everything down itself; its ``summary.json`` is the source of
every figure here (goals reached, contacts and what was touched, wall time). A contact fails the goal.

Why sequential: the demos share a 2-core machine with everything else, and each one's timing (control
latency at the chosen real-time factor) is part of what is measured; running two at once would make
the contacts a measure of the machine, not of navigation.

The generator gives every ``random:N`` at least two rooms (a one-room draw is re-drawn from the seed), so
none is refused; a scene whose waypoints all lie near the start (a hand-written YAML) is refused by
``rbnx demo`` before boot (exit 2) and reported as "refused" with rbnx's reason.
"""

from __future__ import annotations

import argparse
import json
import platform
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "bench" / "results"
BUILTIN = ("apartment", "kitchen", "office", "warehouse")
STOP_WAIT_S = 60.0   # rbnx demo's own shutdown (SIGINT) gets this long before it is killed


def parse_range(text: str) -> list[int]:
    """``1-20`` or ``3,5,9`` or ``1-4,7`` -> the seeds."""
    out: list[int] = []
    for part in text.split(","):
        lo, sep, hi = part.strip().partition("-")
        out += list(range(int(lo), int(hi) + 1)) if sep else [int(lo)]
    return out


def scene_plan(args: argparse.Namespace) -> list[tuple[str, int]]:
    """(scene, goals) in run order."""
    if args.scenes:
        return [(s, args.goals or (args.builtin_goals if s in BUILTIN else args.random_goals)) for s in args.scenes]
    plan: list[tuple[str, int]] = []
    if args.set in ("all", "builtin"):
        plan += [(s, args.goals or args.builtin_goals) for s in BUILTIN]
    if args.set in ("all", "random"):
        plan += [(f"random:{n}", args.goals or args.random_goals) for n in parse_range(args.random)]
    return plan


def run_demo(scene: str, goals: int, out: Path, args: argparse.Namespace) -> dict[str, Any]:
    """One ``rbnx demo``; its summary reduced to the figures of the table (plus the per-goal outcomes)."""
    cmd = [sys.executable, "-m", "rbnx.cli", "demo", "--scene", scene, "--goals", str(goals), "--rtf", f"{args.rtf:g}",
           "--out", str(out), "--timeout-per-goal", f"{args.timeout_per_goal:g}"]
    if args.lidar_noise is not None:
        cmd += ["--lidar-noise", f"{args.lidar_noise[0]:g}", f"{args.lidar_noise[1]:g}"]
    log = out.with_suffix(".log")
    out.parent.mkdir(parents=True, exist_ok=True)
    t0 = time.monotonic()
    with log.open("w") as fh:
        proc = subprocess.Popen(cmd, cwd=ROOT, stdout=fh, stderr=subprocess.STDOUT)
        try:
            rc = proc.wait()
        except KeyboardInterrupt:
            _stop(proc)
            raise
    wall = time.monotonic() - t0
    row: dict[str, Any] = {"scene": scene, "goals_planned": goals, "exit_code": rc, "wall_s": round(wall, 1),
                           "out": str(out), "log": str(log)}
    summary_path = out / "summary.json"
    if rc == 2 or not summary_path.is_file():
        tail = log.read_text(errors="replace").strip().splitlines()[-3:]
        row.update(status="refused" if rc == 2 else "error", reason=" | ".join(tail), goals_reached=0,
                   goals_succeeded=0, contacts=0, touched=[])
        return row
    return {**row, **reduce_summary(json.loads(summary_path.read_text()))}


def _stop(proc: subprocess.Popen[bytes]) -> None:
    """Our own child, by PID: SIGINT (rbnx demo then shuts its system down), kill only if it hangs."""
    if proc.poll() is not None:
        return
    proc.send_signal(signal.SIGINT)
    try:
        proc.wait(STOP_WAIT_S)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


def reduce_summary(s: dict[str, Any]) -> dict[str, Any]:
    """The figures of one demo's summary.json."""
    goals = s.get("goals", [])
    touched = sorted({str(c.get("other_geom", "?")) for g in goals for c in g.get("collisions", [])})
    planned = s.get("goals_planned") or len(goals)
    out = {
        "status": "ok" if s.get("success") else "failed",
        "goals_planned": planned,
        "goals_reached": sum(bool(g.get("reached")) for g in goals),
        "goals_succeeded": s.get("goals_succeeded", 0),
        "contacts": sum(int(g.get("collision_count", 0)) for g in goals),
        "touched": touched,
        "demo_wall_s": s.get("wall_s"),
        # the true body's closest approach to the true obstacles over the demo (robonix_eval/clearance.py)
        "min_clearance_m": min((g["closest"]["clearance_m"] for g in goals if g.get("closest")), default=None),
        "sim_s": round(sum(g.get("duration_sim_s") or 0.0 for g in goals), 1),
        # how far the machine's load shaped the run: the simulator's achieved real-time factor and its waits
        # for a /cmd_vel later than command_lag_bound_s (hal_panda_mobile/loop.py)
        "achieved_rtf": (s.get("sim_loop") or {}).get("achieved_rtf"),
        "cmd_waits": (s.get("sim_loop") or {}).get("cmd_waits"),
        "cmd_wait_timeouts": (s.get("sim_loop") or {}).get("cmd_wait_timeouts"),
        "outcomes": [{"name": g.get("name"), "state": g.get("state"), "contacts": g.get("collision_count", 0),
                      "detail": g.get("detail", ""), "failure": g.get("failure", ""),
                      "closest": g.get("closest"), "collisions": g.get("collisions", [])} for g in goals],
    }
    if s.get("error"):
        out["reason"] = s["error"]
    elif not s.get("success"):
        bad = [g for g in goals if not g.get("succeeded")]
        out["reason"] = "; ".join(f"{g.get('name')}: {g.get('failure') or g.get('state')}" for g in bad[:3])
    return out


def _cm(metres: float | None) -> str:
    return "-" if metres is None else f"{100 * metres:.0f} cm"


def print_table(rows: list[dict[str, Any]]) -> None:
    head = f"{'scene':<12} {'status':<8} {'goals':>7} {'reached':>7} {'contacts':>8} {'closest':>8} {'wall':>7}  notes"
    print(head)
    print("-" * len(head))
    for r in rows:
        note = ", ".join(r.get("touched", [])) or r.get("reason", "")
        print(f"{r['scene']:<12} {r['status']:<8} {r['goals_succeeded']:>3}/{r['goals_planned']:<3} "
              f"{r['goals_reached']:>7} {r['contacts']:>8} {_cm(r.get('min_clearance_m')):>8} {r['wall_s']:>6.0f}s  "
              f"{note[:80]}")
    ran = [r for r in rows if r["status"] != "refused"]
    print(f"{sum(r['goals_succeeded'] for r in ran)}/{sum(r['goals_planned'] for r in ran)} goals succeeded, "
          f"{sum(r['contacts'] for r in ran)} contacts, {sum(r['status'] == 'ok' for r in ran)}/{len(ran)} demos "
          f"clean, {len(rows) - len(ran)} refused", flush=True)
    rtfs = sorted(r["achieved_rtf"] for r in ran if r.get("achieved_rtf") is not None)
    if rtfs:
        print(f"simulator: achieved real-time factor {rtfs[0]:.2f}–{rtfs[-1]:.2f}; waited for a late /cmd_vel "
              f"{sum(r.get('cmd_waits') or 0 for r in ran)} times ({sum(r.get('cmd_wait_timeouts') or 0 for r in ran)} "
              "gave up after 0.4 s of wall time)", flush=True)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--set", choices=("all", "builtin", "random"), default="all",
                    help="which default scene list (ignored with --scenes)")
    ap.add_argument("--scenes", nargs="+", help="explicit scene list, e.g. apartment random:3")
    ap.add_argument("--random", default="1-20", help="random:N seeds, e.g. 1-20 or 2,7 (default 1-20)")
    ap.add_argument("--goals", type=int, help="goals per demo for every scene (overrides the two below)")
    ap.add_argument("--builtin-goals", type=int, default=10)
    ap.add_argument("--random-goals", type=int, default=5)
    ap.add_argument("--rtf", type=float, default=3.0, help="the demo's real-time factor (its default 3)")
    ap.add_argument("--timeout-per-goal", type=float, default=180.0)
    ap.add_argument("--lidar-noise", type=float, nargs=2, metavar=("STD_M", "DROPOUT"),
                    help="simulated lidar range noise and dropout probability (e.g. 0.03 0.05)")
    ap.add_argument("--out", type=Path, default=RESULTS / "demo_scenes.json")
    ap.add_argument("--runs-dir", type=Path, default=RESULTS / "demo_scenes",
                    help="each demo's output directory goes under here")
    args = ap.parse_args(argv)
    plan = scene_plan(args)
    stamp = time.strftime("%Y%m%d-%H%M%S")
    rows: list[dict[str, Any]] = []
    meta = {"rtf": args.rtf, "lidar_noise": args.lidar_noise, "python": platform.python_version(),
            "started": stamp, "command": " ".join(sys.argv)}
    try:
        for i, (scene, goals) in enumerate(plan, 1):
            print(f"[{i}/{len(plan)}] rbnx demo --scene {scene} --goals {goals} …", flush=True)
            row = run_demo(scene, goals, args.runs_dir / stamp / scene.replace(":", "_"), args)
            rows.append(row)
            print(f"    {row['status']}: {row['goals_succeeded']}/{row['goals_planned']} goals, {row['contacts']} "
                  "contacts" + (f" ({', '.join(row['touched'])})" if row["touched"] else "")
                  + f", {row['wall_s']:.0f} s wall" + (f" — {row['reason']}" if row.get("reason") else ""), flush=True)
            args.out.parent.mkdir(parents=True, exist_ok=True)
            args.out.write_text(json.dumps({**meta, "complete": i == len(plan), "rows": rows}, indent=2) + "\n")
    except KeyboardInterrupt:
        print("\ninterrupted: the running demo was stopped; the table shows the finished ones", flush=True)
        if rows:
            print_table(rows)
        return 130
    print()
    print_table(rows)
    print(f"wrote {args.out}")
    return 0 if all(r["status"] in ("ok", "refused") for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
