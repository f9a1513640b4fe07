"""`rbnx replay`: publish a recording on DDS with /clock (the player is :mod:`rbnx.replay`)."""

from __future__ import annotations

import argparse
import signal
import sys
import threading
import time
from typing import Any

from rbnx.replay import Replayer, ReplayError, ReplayStats, parse_remap


def register(sub: Any) -> None:
    """``replay FILE`` and its playback options."""
    r = sub.add_parser("replay", help="publish a recording (.mcap, .db3, rosbag2 dir) on DDS with /clock")
    r.add_argument("file", help="recording: our .mcap, a ROS 2 bag (.mcap / .db3) or a rosbag2 directory")
    r.add_argument("--rate", type=float, default=1.0, help="playback speed factor (default 1.0)")
    r.add_argument("--loop", action="store_true", help="start over at the end")
    r.add_argument("--remap", action="append", default=[], metavar="FROM:=TO", help="topic remap (repeatable)")
    r.add_argument("--topics", nargs="+", metavar="TOPIC", help="replay only these recorded topics")
    r.add_argument("--drop-tf", action="append", default=[], metavar="CHILD_FRAME",
                   help="drop /tf transforms to this child frame (repeatable), e.g. odom")
    r.add_argument("--no-clock", action="store_true", help="publish no /clock")
    r.add_argument("--delay", type=float, default=1.0, help="seconds to wait for subscribers (default 1)")
    r.add_argument("--domain-id", type=int, help="ROS_DOMAIN_ID (default: the environment's)")
    r.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Check the arguments (exit 2), then publish the recording with /clock until its end (or forever with
    ``--loop``)."""
    stop = threading.Event()
    try:
        remaps = dict(parse_remap(a) for a in args.remap)
        if not args.delay >= 0:
            raise ReplayError(f"--delay: must be >= 0, got {args.delay}")
        rep = Replayer(args.file, rate=args.rate, loop=args.loop, remaps=remaps, topics=args.topics,
                       drop_tf=args.drop_tf, clock=not args.no_clock, delay_s=args.delay,
                       domain_id=args.domain_id)
    except ReplayError as exc:
        print(f"rbnx replay: {exc}", file=sys.stderr)
        return 2
    old = {s: signal.signal(s, lambda *_: stop.set()) for s in (signal.SIGINT, signal.SIGTERM)}
    last = [0.0]

    def progress(rel: float, st: ReplayStats) -> None:
        if sys.stdout.isatty() and time.monotonic() - last[0] > 0.5:
            last[0] = time.monotonic()
            print(f"\r{rel:7.1f} / {st.bag_s:.1f} s  {sum(st.published.values())} messages", end="", flush=True)

    try:
        stats = rep.run(stop, progress)
    except ReplayError as exc:
        print(f"rbnx replay: {exc}", file=sys.stderr)
        return 1
    finally:
        for s, h in old.items():
            signal.signal(s, h)
    print(("\ninterrupted: " if stop.is_set() else "\n") + stats.summary(), flush=True)
    return 130 if stop.is_set() else 0
