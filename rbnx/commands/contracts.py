"""`rbnx contracts`: the atlas's contract catalogue."""

from __future__ import annotations

import argparse
import json
from typing import Any

from rbnx.atlas_rpc import KIND_NAMES, Atlas
from rbnx.commands.atlas_view import table, to_dict


def register(sub: Any) -> None:
    """``contracts`` and its options."""
    ct = sub.add_parser("contracts", help="the atlas contract catalogue")
    ct.add_argument("--prefix", default="")
    ct.add_argument("--json", action="store_true")
    ct.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Connect to ``--atlas`` and print its catalogue."""
    with Atlas(args.atlas) as atlas:
        return show(args, atlas)


def show(args: argparse.Namespace, atlas: Atlas) -> int:
    """Print the contracts under ``--prefix`` (table or ``--json``)."""
    cs = atlas.list_contracts(args.prefix or "")
    if args.json:
        print(json.dumps([to_dict(c) for c in cs], indent=2))
        return 0
    rows = [[c.id, KIND_NAMES.get(c.kind, str(c.kind)), c.mode, c.io_srv_type or c.io_msg_type, c.description]
            for c in cs]
    for line in table(rows, ["CONTRACT", "KIND", "MODE", "TYPE", "DESCRIPTION"]):
        print(line)
    return 0
