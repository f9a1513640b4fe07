"""`rbnx logs`: the last lines of a running boot's log files."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from rbnx.boot.deployment import StateNotFound, locate_state
from rbnx.boot.procs import tail
from rbnx.boot.statefile import read_state
from rbnx.commands.common import deploy_arg
from rbnx.models import DEFAULT_DEPLOY


def register(sub: Any) -> None:
    """``logs [-f DEPLOY] [NAME] [-n LINES]``."""
    lg = sub.add_parser("logs", help="tail the logs of a running boot")
    deploy_arg(lg)
    lg.add_argument("name", nargs="?", help="entry name (default: all)")
    lg.add_argument("-n", "--lines", type=int, default=20)
    lg.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Print the last ``-n`` lines of each log of a running boot (or of one entry)."""
    path = Path(args.file or DEFAULT_DEPLOY)
    try:
        st = read_state(locate_state(path, getattr(args, "atlas", None)))
    except StateNotFound as exc:
        print(f"rbnx logs: {exc}", file=sys.stderr)
        return 1
    if st is None:
        print(f"rbnx logs: no running boot recorded for {path}", file=sys.stderr)
        return 1
    log_dir = Path(st["log_dir"])
    names = [args.name] if args.name else ["atlas", *(c["name"] for c in st.get("children", []))]
    for n in names:
        p = log_dir / f"{n}.log"
        print(f"==> {p} <==")
        for line in tail(p, args.lines):
            print(line)
    return 0
