"""`rbnx record`: record DDS topics to an MCAP file (the recorder is :mod:`rbnx.record`)."""

from __future__ import annotations

import argparse
import signal
import sys
import threading
import time
from pathlib import Path
from typing import Any

from rbnx.record import DEFAULT_TOPIC_NAMES, McapRecorder, discover_topics


def register(sub: Any) -> None:
    """``record -o FILE.mcap [TOPIC ...]`` or ``record --format rosbag2 -o FOLDER [TOPIC ...]``."""
    r = sub.add_parser("record", help="record DDS topics to an MCAP file (ROS 2 CDR + ros2msg schemas)")
    r.add_argument("-o", "--output", required=True,
                   help="the .mcap file to write (--format rosbag2: the bag folder to create)")
    r.add_argument("--format", choices=("mcap", "rosbag2"), default="mcap",
                   help="mcap: one .mcap file (default); rosbag2: a folder with metadata.yaml and the .mcap, "
                   "as `ros2 bag record -s mcap` writes it")
    r.add_argument("topics", nargs="*", metavar="TOPIC",
                   help=f"topics (default: {DEFAULT_TOPIC_NAMES}); the type of other topics is learnt from "
                   "their writers, or give it as /name:pkg/Type[:qos]")
    r.add_argument("--duration", type=float, help="stop after this many seconds (default: until Ctrl-C)")
    r.add_argument("--domain-id", type=int, help="ROS_DOMAIN_ID (default: the environment's)")
    r.add_argument("--discovery-timeout", type=float, default=5.0,
                   help="seconds to wait for writers of topics given without a type (default 5)")
    r.add_argument("-q", "--quiet", action="store_true", help="no live message count")
    r.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Check the arguments (exit 2), then record the topics to the .mcap file until Ctrl-C or ``--duration``."""
    from rbnx.rosmsg import DEFAULT_TOPICS, KNOWN, TopicError, parse_topic

    names = list(dict.fromkeys("/" + t.strip().lstrip("/") if ":" not in t else t for t in args.topics))
    unknown = [n for n in names if ":" not in n and n not in KNOWN]
    try:
        specs = [parse_topic(t) for t in names if t not in unknown] if names else list(DEFAULT_TOPICS)
    except TopicError as exc:
        print(f"rbnx record: {exc}", file=sys.stderr)
        return 2
    if unknown:
        try:
            specs += discover_topics(unknown, args.domain_id, args.discovery_timeout)
        except TopicError as exc:
            print(f"rbnx record: {exc}", file=sys.stderr)
            return 2
    if args.duration is not None and not args.duration > 0:
        print(f"rbnx record: --duration: must be > 0, got {args.duration}", file=sys.stderr)
        return 2
    out = Path(args.output)
    if args.format == "mcap" and out.suffix != ".mcap":
        print(f"rbnx record: --output {out}: must end in .mcap", file=sys.stderr)
        return 2
    if args.format == "rosbag2" and out.exists():
        print(f"rbnx record: --output {out}: exists already; give a new bag folder name", file=sys.stderr)
        return 2
    if not out.parent.is_dir():
        print(f"rbnx record: --output {out}: directory {out.parent} does not exist", file=sys.stderr)
        return 2
    stop = threading.Event()
    old = {s: signal.signal(s, lambda *_: stop.set()) for s in (signal.SIGINT, signal.SIGTERM)}
    if args.format == "rosbag2":
        from rbnx.rosbag2_out import Rosbag2Recorder

        rec: McapRecorder = Rosbag2Recorder(out, specs, args.domain_id)
    else:
        rec = McapRecorder(out, specs, args.domain_id)
    try:
        rec.start()
        print(f"recording {', '.join(s.topic for s in specs)} to {out} (Ctrl-C stops)", flush=True)
        deadline = None if args.duration is None else time.monotonic() + args.duration
        while not stop.is_set() and (deadline is None or time.monotonic() < deadline):
            stop.wait(0.5 if deadline is None else max(0.0, min(0.5, deadline - time.monotonic())))
            if not args.quiet and sys.stdout.isatty():
                print(f"\r{rec.summary()}", end="", flush=True)
    except OSError as exc:
        print(f"rbnx record: {out}: {exc.strerror or exc}", file=sys.stderr)
        return 1
    finally:
        rec.stop()
        for s, h in old.items():
            signal.signal(s, h)
    print(f"\n{out}: {rec.summary()}", flush=True)
    return 0
