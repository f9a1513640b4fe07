"""`rbnx caps`: the providers registered at the atlas, their states and capabilities."""

from __future__ import annotations

import argparse
import json
from typing import Any

from rbnx.atlas_rpc import KIND_NAMES, STATE_NAMES, TRANSPORT_NAMES, Atlas, params_text
from rbnx.boot.statefile import restarts_for_atlas
from rbnx.commands.atlas_view import age, endpoint, to_dict


def register(sub: Any) -> None:
    """``caps`` and its options."""
    c = sub.add_parser("caps", help="providers and their capabilities")
    c.add_argument("--json", action="store_true")
    c.add_argument("-v", "--verbose", action="store_true", help="endpoints, params, heartbeat age")
    c.add_argument("--kind", choices=("primitive", "service", "skill"))
    c.add_argument("--id", help="only this provider")
    c.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Connect to ``--atlas`` and print its providers."""
    with Atlas(args.atlas) as atlas:
        return show(args, atlas)


def show(args: argparse.Namespace, atlas: Atlas) -> int:
    """Print the providers at ``atlas`` (table or ``--json``), with endpoints when ``-v``."""
    kind = {"primitive": 1, "service": 2, "skill": 3}.get(args.kind or "", 0)
    provs = sorted(atlas.query(kind=kind, id=args.id or ""), key=lambda p: p.id)
    restarts = restarts_for_atlas(atlas.addr)
    if args.json:
        out = []
        for p in provs:
            d = to_dict(p)
            if args.verbose:
                for c, cd in zip(p.capabilities, d.get("capabilities", []), strict=True):
                    cd["endpoint"] = endpoint(atlas, p.id, c)
            else:
                d.pop("capability_md", None)
            d["restarts"] = restarts.get(p.id, 0)
            out.append(d)
        print(json.dumps(out, indent=2))
        return 0
    if not provs:
        print(f"no providers registered at {atlas.addr}")
        return 0
    if restarts.get("atlas"):
        print(f"(atlas restarted {restarts['atlas']} time(s) by rbnx boot)")
    for p in provs:
        state = STATE_NAMES.get(p.state, str(p.state))
        detail = f" ({p.state_detail})" if p.state_detail else ""
        print(f"{p.id}  [{KIND_NAMES.get(p.kind, p.kind)}]  {state}{detail}  ns={p.namespace}"
              + (f"  restarts {restarts[p.id]}" if restarts.get(p.id) else "")
              + (f"  heartbeat {age(p.last_heartbeat_ms)}" if args.verbose else ""))
        for c in sorted(p.capabilities, key=lambda c: (c.contract_id, c.transport)):
            line = f"    {c.contract_id:<44} {TRANSPORT_NAMES.get(c.transport, c.transport):<5}"
            if args.verbose:
                line += f" {endpoint(atlas, p.id, c)}  {params_text(c.params)}  {c.description}"
            print(line.rstrip())
    return 0
