"""`rbnx channels`: the channels open at the atlas (from InspectAtlas)."""

from __future__ import annotations

import argparse
import json
from typing import Any

from rbnx.atlas_rpc import Atlas
from rbnx.commands.atlas_view import table


def register(sub: Any) -> None:
    """``channels`` and its options."""
    ch = sub.add_parser("channels", help="open channels (from InspectAtlas)")
    ch.add_argument("--json", action="store_true")
    ch.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Connect to ``--atlas`` and print its open channels."""
    with Atlas(args.atlas) as atlas:
        return show(args, atlas)


def show(args: argparse.Namespace, atlas: Atlas) -> int:
    """Print the channels InspectAtlas lists (table or ``--json``)."""
    data = atlas.inspect()
    chans = data.get("channels", []) if isinstance(data, dict) else []
    if isinstance(chans, dict):
        chans = [{"channel_id": k, **(v if isinstance(v, dict) else {"value": v})} for k, v in chans.items()]
    if args.json:
        print(json.dumps(chans, indent=2))
        return 0
    if not chans:
        print("no open channels")
        return 0
    keys = ["channel_id", "consumer_id", "provider_id", "contract_id", "transport", "endpoint"]
    rows = [[str(c.get(k, "")) for k in keys] for c in chans if isinstance(c, dict)]
    for line in table(rows, [k.upper() for k in keys]):
        print(line)
    return 0
