"""`rbnx dashboard`: serve the live web dashboard on 127.0.0.1 until Ctrl-C."""

from __future__ import annotations

import argparse
import signal
import sys
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

from rbnx.dashboard.launch import DEFAULT_PORT, atlas_of_deploy, check_port, start_background


def register(sub: Any) -> None:
    """``dashboard [--port] [--host] [-f DEPLOY]``."""
    d = sub.add_parser("dashboard", help="live web dashboard on 127.0.0.1 (map, robot, plan, scan, goals, lifecycle)")
    d.add_argument("--port", type=int, default=DEFAULT_PORT, help=f"port (default {DEFAULT_PORT}; 0 = any free)")
    d.add_argument("--host", default="127.0.0.1", help="address to bind (default 127.0.0.1)")
    d.add_argument("-f", "--file", help="find the atlas of the running boot of this deploy file (else --atlas)")
    d.add_argument("--domain-id", type=int, help="ROS_DOMAIN_ID (default: the environment's)")
    d.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Serve the dashboard for ``--atlas`` (or the boot of ``-f``) until Ctrl-C; exit 2 for a bad port or file."""
    problem = check_port(args.port)
    if problem:
        print(f"rbnx dashboard: {problem}", file=sys.stderr)
        return 2
    atlas: str | Callable[[], str | None] = args.atlas
    if args.file:
        deploy = Path(args.file)
        if not deploy.is_file():
            print(f"rbnx dashboard: -f {deploy}: no such deploy file", file=sys.stderr)
            return 2
        atlas = atlas_of_deploy(deploy)
    try:
        server = start_background(atlas, args.port, args.domain_id, args.host)
    except OSError as exc:
        print(f"rbnx dashboard: {exc}", file=sys.stderr)
        return 1
    print(f"dashboard at {server.url} (Ctrl-C stops)", flush=True)
    stop = threading.Event()
    old = {s: signal.signal(s, lambda *_: stop.set()) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        while not stop.is_set() and server.running():
            stop.wait(0.5)
    finally:
        server.stop()
        for s, h in old.items():
            signal.signal(s, h)
    return 0
