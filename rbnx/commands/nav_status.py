"""`rbnx nav-status`: the state of a navigation run (default: the latest), from the navigation provider."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from rbnx.demo.boot import DemoError
from rbnx.demo.rpc import DemoRpc


def register(sub: Any) -> None:
    """``nav-status [RUN_ID]``."""
    s = sub.add_parser("nav-status", help="state of a navigation run (default: the latest)")
    s.add_argument("run_id", nargs="?", default="", help="run id (default: the latest run)")
    s.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Print the state of a run (default the latest); exit 1 when it is unknown or the provider is unreachable."""
    rpc = DemoRpc(args.atlas)
    try:
        st = rpc.status(args.run_id)
    except DemoError as exc:
        print(f"rbnx nav-status: {exc}", file=sys.stderr)
        return 1
    finally:
        rpc.close()
    if not st.known:
        print(f"rbnx nav-status: {args.run_id or 'latest run'}: unknown ({st.detail})", file=sys.stderr)
        return 1
    print(f"{st.state}: {st.detail}")
    return 0
