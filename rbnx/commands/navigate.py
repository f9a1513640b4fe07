"""`rbnx navigate`: send a goal from a terminal and follow it (`nav-status`, `cancel` are its siblings).

The navigation provider is found through the atlas like any consumer finds it (contracts
robonix/service/navigation/navigate{,/status,/cancel} over gRPC). `navigate` shows a live progress line
until the run ends; Ctrl-C cancels the goal before exiting (130). While navigation (or the atlas) restarts,
status calls fail: `navigate` keeps following the same run id, looking the provider up again, for up to
RECONNECT_S seconds (the robot may still be driving: never give up on it silently). Exit codes: 0 SUCCEEDED (or, for
nav-status/cancel, the call worked); 1 the goal failed/was canceled or the system is unreachable;
2 bad arguments.
"""

from __future__ import annotations

import argparse
import math
import signal
import sys
import threading
import time
from typing import Any

from rbnx.demo.boot import DemoError
from rbnx.demo.goals import TERMINAL, Goal, warming_up
from rbnx.demo.report import LiveLine
from rbnx.demo.rpc import CANCEL, STATUS, DemoRpc

#: How long `navigate` keeps asking a navigation provider that stopped answering (a restart takes a few s)
RECONNECT_S = 60.0


def register(sub: Any) -> None:
    """``navigate X Y [--yaw] [--frame] [--timeout] [--no-wait]``."""
    n = sub.add_parser("navigate", help="send a navigation goal and follow it (Ctrl-C cancels it)")
    n.add_argument("x", type=float, help="goal x in metres")
    n.add_argument("y", type=float, help="goal y in metres")
    n.add_argument("--yaw", type=float, default=0.0, help="goal heading in radians (default 0)")
    n.add_argument("--frame", default="map", help="frame of the goal (default map)")
    n.add_argument("--timeout", type=float, default=0.0, help="give up (and cancel) after S seconds; 0 = never")
    n.add_argument("--no-wait", action="store_true", help="print the run id and return at once")
    n.set_defaults(run=run)


def _check(args: argparse.Namespace) -> str | None:
    for name in ("x", "y", "yaw"):
        if not math.isfinite(getattr(args, name)):
            return f"{name}: must be a finite number, got {getattr(args, name)}"
    if not args.frame.strip():
        return "--frame: must not be empty"
    if not (math.isfinite(args.timeout) and args.timeout >= 0):
        return f"--timeout: must be >= 0, got {args.timeout}"
    return None


def run(args: argparse.Namespace) -> int:
    """Send the goal, then follow it to the end (exit 0 only on SUCCEEDED); Ctrl-C cancels it (exit 130)."""
    problem = _check(args)
    if problem:
        print(f"rbnx navigate: {problem}", file=sys.stderr)
        return 2
    rpc = DemoRpc(args.atlas)
    stop = threading.Event()
    old = signal.signal(signal.SIGINT, lambda *_: stop.set())
    run_id = ""
    try:
        accepted, run_id, detail = rpc.navigate(Goal("cli", args.x, args.y, args.yaw), args.frame.strip())
        if not accepted:
            print(f"rbnx navigate: goal rejected: {detail}", file=sys.stderr)
            return 1
        print(f"goal ({args.x:g}, {args.y:g}, yaw {args.yaw:g}) in {args.frame}: run {run_id}", flush=True)
        if args.no_wait:
            return 0
        return _follow(rpc, run_id, stop, args.timeout)
    except DemoError as exc:
        print(f"rbnx navigate: {exc}", file=sys.stderr)
        return 1
    finally:
        signal.signal(signal.SIGINT, old)
        rpc.close()


def _follow(rpc: DemoRpc, run_id: str, stop: threading.Event, timeout: float) -> int:
    line = LiveLine()
    t0 = t_limit = time.monotonic()
    lost: float | None = None  # when status stopped answering
    while True:
        if stop.is_set() or (timeout and time.monotonic() - t_limit > timeout):
            why = "interrupted" if stop.is_set() else f"timeout after {timeout:g}s"
            accepted, detail = rpc.cancel_run(run_id)
            line.done(f"{why}: cancel {'sent' if accepted else 'refused'} ({detail})")
            return 130 if stop.is_set() else 1
        try:
            st = rpc.status(run_id)
        except DemoError as exc:  # navigation (or the atlas) restarting: follow the same run when it is back
            lost = lost if lost is not None else time.monotonic()
            if time.monotonic() - lost > RECONNECT_S:
                raise DemoError(f"{exc} (no answer for {RECONNECT_S:g} s; run {run_id} may still be driving: "
                                f"rbnx nav-status {run_id})") from None
            line.update("RECONNECTING", f"RECONNECTING {time.monotonic() - t0:5.1f}s  {exc}")
            rpc.forget(STATUS)
            rpc.forget(CANCEL)
            stop.wait(0.5)
            continue
        lost = None
        if not st.known:
            line.done(f"run {run_id}: unknown to the navigation provider ({st.detail})")
            return 1
        if warming_up(st.state, st.detail):
            t_limit = time.monotonic()  # --timeout starts when the planner's first-run warm-up ended
        line.update(st.state, f"{st.state} {time.monotonic() - t0:5.1f}s  {st.detail}")
        if st.state in TERMINAL:
            line.done(f"{st.state}: {st.detail}")
            return 0 if st.state == "SUCCEEDED" else 1
        stop.wait(0.5)
