"""`rbnx token`: print the running deployment's token, for agents and scripts that call it directly.

    export ROBONIX_DEPLOY_TOKEN=$(rbnx token)          # our SDK's clients send it from then on
    curl -H "Authorization: Bearer $(rbnx token)" …     # an MCP client: the gateway wants this header
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from rbnx.boot import deploytoken
from rbnx.boot.statefile import read_state


def register(sub: Any) -> None:
    """``token [-f DEPLOY]``."""
    t = sub.add_parser("token", help="print the deployment token of a running boot (for agents)")
    t.add_argument("-f", "--file", help="deploy file of the boot (default: the boot serving --atlas)")
    t.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Print the deployment token of the boot serving ``--atlas`` (or of ``-f``); exit 1 when none is recorded."""
    token = ""
    if args.file:
        from rbnx.boot.deployment import StateNotFound, locate_state

        try:
            token = deploytoken.token_of_state(read_state(locate_state(Path(args.file), args.atlas)))
        except StateNotFound as exc:
            print(f"rbnx token: {exc}", file=sys.stderr)
            return 1
    else:
        token = deploytoken.token_for_atlas(args.atlas)
    if not token:
        where = args.file or f"atlas {args.atlas}"
        print(f"rbnx token: no deployment token recorded for {where} (not booted by rbnx boot on this host, "
              "or booted with system.atlas.auth: none)", file=sys.stderr)
        return 1
    print(token)
    return 0
