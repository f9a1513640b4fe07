"""`rbnx inspect`: the atlas's InspectAtlas JSON as it is."""

from __future__ import annotations

import argparse
import json
from typing import Any

from rbnx.atlas_rpc import Atlas


def register(sub: Any) -> None:
    """``inspect`` and its options."""
    i = sub.add_parser("inspect", help="InspectAtlas JSON")
    i.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Connect to ``--atlas`` and print its InspectAtlas JSON."""
    with Atlas(args.atlas) as atlas:
        return show(args, atlas)


def show(args: argparse.Namespace, atlas: Atlas) -> int:
    """Print InspectAtlas as sorted, indented JSON."""
    print(json.dumps(atlas.inspect(), indent=2, sort_keys=True))
    return 0
