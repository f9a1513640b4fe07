"""`rbnx demo`: the main job in one command — boot the sim deploy, map while navigating to N goals with
live progress, write map.png + summary.json, shut everything down (also on Ctrl-C).

The system runs under `rbnx boot` as a child process (its own atlas on a loopback port chosen by the OS,
its own ROS_DOMAIN_ID), so the demo is an ordinary robonix consumer: gRPC contracts found through the
atlas, /plan, /map and TF over DDS. Exit codes: 0 every goal succeeded; 1 a goal or the system failed;
2 a usage error (nothing started); 130 interrupted.
"""

from __future__ import annotations

import argparse
import importlib.util
import math
import os
import signal
import sys
import threading
import time
from pathlib import Path
from types import FrameType
from typing import Any

from rbnx.demo.boot import BootChild, DemoError, pick_domain_id
from rbnx.demo.goalrun import GoalRunner
from rbnx.demo.goals import Goal, choose_goals, fmt_s
from rbnx.demo.live import DemoLive
from rbnx.demo.record import Recorder, render_map
from rbnx.demo.report import GoalResult, LiveLine, goals_exit_code, print_table, write_json
from rbnx.demo.rpc import DemoRpc
from rbnx.demo.variant import write_variant
from robonix_common.jit_cache import writable_dir
from robonix_nav_data import resources

DEFAULT_DEPLOY = Path("examples") / "sim" / "deploy.yaml"
REPO_DEPLOY = resources.example_deploy("sim")
MIN_GOAL_DIST_M = 1.0


def register(sub: Any) -> None:
    """``demo`` and its options."""
    d = sub.add_parser("demo", help="boot the simulated robot, map while navigating to N goals, write map.png")
    d.add_argument("--scene", default="apartment",
                   help="apartment|kitchen|office|warehouse|random[:SEED] or a scene YAML (default apartment)")
    d.add_argument("--goals", type=int, default=3, help="number of goals (default 3)")
    d.add_argument("--rtf", type=float, default=3.0, help="sim real-time factor; 0 = as fast as possible (default 3)")
    d.add_argument("--seed", type=int, help="shuffle the scene's waypoints with this seed (default: file order)")
    d.add_argument("--out", help="output directory (default ./rbnx-demo/<timestamp>)")
    d.add_argument("-f", "--deploy", "--file", dest="deploy", help=f"deploy file (default {DEFAULT_DEPLOY})")
    d.add_argument("--timeout-per-goal", type=float, default=180.0, help="wall seconds per goal (default 180)")
    d.add_argument("--boot-timeout", type=float, default=120.0, help="wall seconds to come up (default 120)")
    d.add_argument("--lidar-noise", type=float, nargs=2, metavar=("STD_M", "DROPOUT"),
                   help="simulated lidar range noise (m, Gaussian) and per-beam dropout probability, e.g. 0.03 0.05 "
                        "(default: the robot description's)")
    d.add_argument("--record", action="store_true", help="record the run to OUT/run.mcap (MCAP, ROS 2 CDR)")
    d.add_argument("--dashboard", type=int, nargs="?", const=8765, metavar="PORT",
                   help="serve the live dashboard on 127.0.0.1:PORT (default 8765)")
    d.set_defaults(run=run)


# ---------------------------------------------------------------------- argument checks (exit 2)


class UsageError(ValueError):
    """A user mistake: one line, exit 2, nothing started."""


def builtin_scenes() -> list[str]:
    """Scene names from hal_panda_mobile/scenes without importing the simulator (MuJoCo is slow to load)."""
    spec = importlib.util.find_spec("hal_panda_mobile")
    roots = list(spec.submodule_search_locations or []) if spec else []
    names = {p.stem for r in roots for p in (Path(r) / "scenes").glob("*.yaml")}
    return sorted(names | {"random"})


def resolve_scene(scene: str) -> str:
    """A built-in scene name, ``random:SEED`` or an existing scene YAML (made absolute), else UsageError."""
    if scene in builtin_scenes():
        return scene
    if scene.startswith("random:"):
        if not scene.partition(":")[2].lstrip("-").isdigit():
            raise UsageError(f"--scene {scene}: random seed must be an integer (e.g. random:3)")
        return scene
    p = Path(scene)
    if p.suffix in (".yaml", ".yml") and p.is_file():
        return str(p.resolve())  # boot runs the HAL in its package dir: hand it an absolute path
    raise UsageError(f"--scene: unknown scene {scene!r}; available: {', '.join(builtin_scenes())}, "
                     "random:<seed>, or a scene YAML file")


def check_scene_goals(scene: str) -> None:
    """A ``random:N`` scene is generated here (deterministically, as the simulator will) and a scene YAML is
    loaded, so that one whose waypoints all lie within MIN_GOAL_DIST_M of the start is refused before anything
    is booted. (The generator always gives two rooms or more; a hand-written YAML may still have nothing to
    drive to.) Built-in scenes are checked by their own tests and skip the simulator import here."""
    if scene in builtin_scenes() and scene != "random":
        return
    from hal_panda_mobile.files.scene import load_scene
    from hal_panda_mobile.sim import SimConfigError

    try:
        s = load_scene(scene)
    except SimConfigError as exc:
        raise UsageError(f"--scene {scene}: {exc}") from exc
    if not choose_goals(dict(s.waypoints), (s.start[0], s.start[1]), 1, None, MIN_GOAL_DIST_M):
        raise UsageError(f"--scene {scene}: no waypoint farther than {MIN_GOAL_DIST_M:g} m from the start "
                         "(nothing to navigate to); pick another seed")


def resolve_deploy(arg: str | None) -> Path:
    """The deploy file to boot: ``--deploy``, else ./examples/sim/deploy.yaml, else the packaged one."""
    if arg:
        p = Path(arg)
        if not p.is_file():
            raise UsageError(f"--deploy: deploy file {arg} not found")
        return p.resolve()
    return (DEFAULT_DEPLOY if DEFAULT_DEPLOY.is_file() else REPO_DEPLOY).resolve()


def _check_args(args: argparse.Namespace) -> tuple[Path, str, Path]:
    if args.goals < 1:
        raise UsageError(f"--goals: must be >= 1, got {args.goals}")
    if not (math.isfinite(args.rtf) and args.rtf >= 0):
        raise UsageError(f"--rtf: must be >= 0 (0 = as fast as possible), got {args.rtf}")
    for name in ("timeout_per_goal", "boot_timeout"):
        v = getattr(args, name)
        if not (math.isfinite(v) and v > 0):
            raise UsageError(f"--{name.replace('_', '-')}: must be > 0, got {v}")
    if args.lidar_noise is not None:
        std, drop = args.lidar_noise
        if not (math.isfinite(std) and std >= 0 and 0 <= drop <= 1):
            raise UsageError(f"--lidar-noise: need STD_M >= 0 and 0 <= DROPOUT <= 1, got {std:g} {drop:g}")
    if args.dashboard is not None and not 0 <= args.dashboard <= 65535:
        raise UsageError(f"--dashboard: port must be 0..65535, got {args.dashboard}")
    deploy = resolve_deploy(args.deploy)
    if not deploy.is_file():
        raise UsageError(f"deploy file {deploy} not found (pass --deploy)")
    scene = resolve_scene(args.scene)
    check_scene_goals(scene)
    out = Path(args.out) if args.out else Path("rbnx-demo") / time.strftime("%Y%m%d-%H%M%S")
    if out.exists() and not out.is_dir():
        raise UsageError(f"--out: {out} exists and is not a directory")
    if not writable_dir(out):  # e.g. a read-only container's working folder: say so before booting anything
        where = "--out" if args.out else "the default output folder"
        raise UsageError(f"{where} {out.resolve()} cannot be written (read-only filesystem?); "
                         "pass --out DIR on a writable one, e.g. --out /tmp/rbnx-demo")
    return deploy, scene, out.resolve()


# ---------------------------------------------------------------------- signals


class _Stop:
    """SIGINT/SIGTERM/SIGHUP set an event (loops notice within a poll); a second one makes boot hurry."""

    def __init__(self) -> None:
        self.event = threading.Event()
        self.count = 0
        self.boot: BootChild | None = None
        self._old: dict[int, Any] = {}

    def _handler(self, signum: int, _frame: FrameType | None) -> None:
        self.count += 1
        if self.count == 1:
            print(f"\n{signal.Signals(signum).name}: stopping the demo and shutting down…", file=sys.stderr)
        elif self.boot is not None:
            self.boot.interrupt()
        self.event.set()

    def __enter__(self) -> _Stop:
        for s in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
            self._old[s] = signal.signal(s, self._handler)
        return self

    def __exit__(self, *_: Any) -> None:
        for s, h in self._old.items():
            signal.signal(s, h)


# ---------------------------------------------------------------------- the command


def _wait_line(line: LiveLine, names: list[str], t0: float) -> Any:
    def show(states: dict[str, str]) -> None:
        parts = ", ".join(f"{n} {states.get(n, '…')}" for n in names)
        line.update("boot", f"booting: {parts} ({time.monotonic() - t0:.0f}s)")
    return show


def run(args: argparse.Namespace) -> int:
    """Boot the sim, map while driving to the goals, write map.png and summary.json; exit 0 only when every goal
    succeeded."""
    from rbnx.models import load_deploy

    try:
        deploy_path, scene, out = _check_args(args)
    except UsageError as exc:
        print(f"rbnx demo: {exc}", file=sys.stderr)
        return 2
    if args.lidar_noise is not None:
        try:
            deploy_path = write_variant(deploy_path, out, {"lidar_noise": {"noise_std": args.lidar_noise[0],
                                                                           "dropout_prob": args.lidar_noise[1]}})
        except ValueError as exc:
            print(f"rbnx demo: --lidar-noise: {exc}", file=sys.stderr)
            return 2
    env = dict(os.environ)
    env.update(RBNX_SIM_SCENE=scene, RBNX_SIM_RTF=f"{args.rtf:g}", PYTHONUNBUFFERED="1",
               RBNX_STATE_DIR=str(out / "state"))
    env.setdefault("RBNX_ATLAS_LISTEN", "127.0.0.1:0")  # the OS picks a free loopback port; boot reports it
    env.pop("ROBONIX_ATLAS", None)
    if not env.get("ROS_DOMAIN_ID", "").strip():
        env["ROS_DOMAIN_ID"] = str(pick_domain_id())
    domain = int(env["ROS_DOMAIN_ID"])
    deploy = load_deploy(deploy_path, base_env=env)  # ManifestProblems -> exit 2, nothing started
    if args.rtf == 0 or args.rtf > 8:
        print(f"note: --rtf {args.rtf:g} can outrun SLAM + navigation on a small machine (runs then fail with "
              "'TF map→base_link is stale'); 3-6 is reliable", file=sys.stderr)
    names = [e.name for e in deploy.entries if e.kind != "skill"]
    out.mkdir(parents=True, exist_ok=True)

    boot = BootChild(deploy_path, out, env, boot_timeout=args.boot_timeout)
    line = LiveLine()
    results: list[GoalResult] = []
    goals: list[Goal] = []
    summary: dict[str, Any] = {"success": False, "scene": scene, "rtf": args.rtf, "seed": args.seed,
                               "deploy": str(deploy_path), "ros_domain_id": domain, "out": str(out),
                               "lidar_noise": args.lidar_noise, "logs": str(boot.log_dir),
                               "started": time.strftime("%Y-%m-%dT%H:%M:%S%z")}
    code, t_start = 1, time.monotonic()
    rpc: DemoRpc | None = None
    rec: Recorder | None = None
    live = DemoLive(args.record, args.dashboard, out, domain)
    with _Stop() as stop:
        stop.boot = boot
        try:
            print(f"rbnx demo: booting {deploy_path.name} (scene {scene}, rtf {args.rtf:g}, ROS_DOMAIN_ID "
                  f"{domain}); logs in {boot.log_dir}", flush=True)
            boot.start()
            atlas = boot.wait_active(names, args.boot_timeout + 30.0, stop.event,
                                     _wait_line(line, names, t_start))
            line.done(f"system up in {time.monotonic() - t_start:.1f}s: {', '.join(names)} ACTIVE, atlas {atlas}")
            summary["atlas"] = atlas
            live.start(atlas, summary)
            rpc = DemoRpc(atlas)
            rec = Recorder(rpc, domain)
            rec.start()
            rec.wait_ready(20.0, stop.event)
            info = rpc.scene_info()
            gt = rpc.ground_truth()
            goals = choose_goals(info.get("waypoints") or {}, (gt.x, gt.y), args.goals, args.seed, MIN_GOAL_DIST_M)
            if not goals:
                raise DemoError(f"scene {info.get('name', scene)!r} has no waypoint farther than "
                                f"{MIN_GOAL_DIST_M:g} m from the robot; pick another --scene")
            print(f"{len(goals)} goal(s) in scene {info.get('name')}: "
                  + ", ".join(f"{g.name} ({g.x:.2f}, {g.y:.2f})" for g in goals), flush=True)
            runner = GoalRunner(rpc, rec, boot, stop.event, args.timeout_per_goal, line,
                                _clearance_field(scene, info.get("name"), rec))
            for i, g in enumerate(goals, 1):
                if stop.event.is_set():
                    break
                results.append(runner.run(GoalResult(i, g), len(goals)))
            code = goals_exit_code(results, len(goals))
        except DemoError as exc:
            line.done(f"rbnx demo: {exc}")
            for ln in exc.lines:
                print(f"    | {ln}", flush=True)
            summary["error"] = str(exc)
        except KeyboardInterrupt:
            pass
        finally:
            live.stop(summary)
            code = _finish(code, stop, boot, rpc, rec, results, goals, summary, out, t_start)
    return code


def _clearance_field(scene: str, sim_name: str | None, rec: Recorder) -> Any:
    """The ground-truth clearance field for the scene the simulator loaded, or None (with a warning) when it
    cannot be built here or names another scene: the closest-approach figures are then left out."""
    from robonix_eval.clearance import ClearanceField

    try:
        field = ClearanceField.for_scene(scene)
    except Exception as exc:  # a figure of the report, never a reason to fail the demo
        rec.warnings.append(f"clearance: not measured ({type(exc).__name__}: {exc})")
        return None
    if sim_name and field.scene_name != sim_name:
        rec.warnings.append(f"clearance: not measured (simulator scene {sim_name!r}, here {field.scene_name!r})")
        return None
    return field


def _note_sim_loop(rpc: DemoRpc, summary: dict[str, Any]) -> None:
    """The simulator's loop figures (achieved real-time factor, waits for a late /cmd_vel) into the summary
    (``_finish`` prints them after the goal table): they say how far the machine's load shaped the run."""
    try:
        loop = rpc.scene_info().get("loop") or {}
    except Exception as exc:  # a figure of the report, never a reason to fail the demo
        print(f"warning: simulator loop figures not read: {type(exc).__name__}: {exc}", file=sys.stderr)
        return
    summary["sim_loop"] = loop


def _finish(code: int, stop: _Stop, boot: BootChild, rpc: DemoRpc | None, rec: Recorder | None,
            results: list[GoalResult], goals: list[Goal], summary: dict[str, Any], out: Path,
            t_start: float) -> int:
    """Always: map.png and summary.json from whatever ran, then shut the system down and check for leftovers."""
    interrupted = stop.event.is_set()
    if interrupted:
        summary["interrupted"] = True
        code = 130
    map_png = out / "map.png"
    if rec is not None and rpc is not None and boot.running():
        plans = [r.plan for r in results if r.plan is not None]
        try:
            summary["map_png"] = str(map_png)
            summary["map"] = render_map(map_png, rec, rpc, plans)
        except DemoError as exc:
            summary.pop("map_png", None)
            rec.warnings.append(f"map.png: {exc}")
            print(f"warning: map.png not written: {exc}", file=sys.stderr)
    if rpc is not None and boot.running():
        _note_sim_loop(rpc, summary)
    if rec is not None:
        rec.stop()
        summary["warnings"] = rec.warnings
    if rpc is not None:
        rpc.close()
    summary["goals"] = [r.as_dict() for r in results]
    summary["goals_planned"] = len(goals)
    summary["goals_succeeded"] = sum(r.succeeded for r in results)
    summary["success"] = code == 0
    if results:
        print()
        print_table(results, len(goals))
    loop = summary.get("sim_loop") or {}
    if "achieved_rtf" in loop:
        print(f"simulator: achieved real-time factor {loop['achieved_rtf']:.2f}; waited for a late /cmd_vel "
              f"{loop.get('cmd_waits', 0)} time(s), {loop.get('cmd_wait_wall_s', 0.0):.1f} s of wall time", flush=True)
    print("shutting down…", flush=True)
    leftovers = boot.stop()
    summary["wall_s"] = round(time.monotonic() - t_start, 2)
    summary["leftover_processes"] = leftovers
    if leftovers:
        print(f"rbnx demo: processes still running after shutdown: {', '.join(leftovers)}", file=sys.stderr)
        code = code or 1
        summary["success"] = False
    boot_rc = boot.proc.returncode if boot.proc is not None else None
    summary["boot_exit_code"] = boot_rc
    write_json(out / "summary.json", summary)
    print(f"stopped (rbnx boot exit {boot_rc}); summary {out / 'summary.json'}"
          + (f", map {map_png}" if "map_png" in summary else "") + f", logs {boot.log_dir}", flush=True)
    print("result: " + ("SUCCESS" if code == 0 else "INTERRUPTED" if code == 130 else "FAILED")
          + f" ({summary['goals_succeeded']}/{len(goals)} goals) in {fmt_s(summary['wall_s'])}", flush=True)
    return code
