"""`rbnx cancel`: cancel a navigation run (default: the latest); exit 1 when the provider refuses."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from rbnx.demo.boot import DemoError
from rbnx.demo.rpc import DemoRpc


def register(sub: Any) -> None:
    """``cancel [RUN_ID]``."""
    c = sub.add_parser("cancel", help="cancel a navigation run (default: the latest)")
    c.add_argument("run_id", nargs="?", default="", help="run id (default: the latest run)")

    c.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Cancel a run through the navigation provider's cancel contract; exit 1 when it refuses or is unreachable."""
    rpc = DemoRpc(args.atlas)
    try:
        accepted, detail = rpc.cancel_run(args.run_id)
    except DemoError as exc:
        print(f"rbnx cancel: {exc}", file=sys.stderr)
        return 1
    finally:
        rpc.close()
    print(("canceled: " if accepted else "not canceled: ") + detail)
    return 0 if accepted else 1
