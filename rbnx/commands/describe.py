"""`rbnx describe`: one provider in detail (or, with --check, a one-line health check)."""

from __future__ import annotations

import argparse
import json
from typing import Any

from rbnx.atlas_rpc import KIND_NAMES, STATE_NAMES, TRANSPORT_NAMES, Atlas, params_text
from rbnx.commands.atlas_view import age, endpoint, to_dict


def register(sub: Any) -> None:
    """``describe`` and its options."""
    d = sub.add_parser("describe", help="one provider in detail")
    d.add_argument("--provider", required=True)
    d.add_argument("--json", action="store_true")
    d.add_argument("--check", action="store_true",
                   help="health check: one line, exit 0 only if registered and not TERMINATED/ERROR")
    d.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Connect to ``--atlas`` and describe one provider."""
    with Atlas(args.atlas) as atlas:
        return show(args, atlas)


def show(args: argparse.Namespace, atlas: Atlas) -> int:
    """Print one provider in detail, or with ``--check`` one health line (exit 1 if gone or failed)."""
    p = atlas.provider(args.provider)
    if p is None:
        print(f"rbnx describe: no provider {args.provider!r} at {atlas.addr}")
        return 1
    state = STATE_NAMES.get(p.state, str(p.state))
    if getattr(args, "check", False):  # container healthcheck: registered and alive
        healthy = state not in ("terminated", "error")
        print(f"{p.id}: {state}" + (f" ({p.state_detail})" if p.state_detail else ""))
        return 0 if healthy else 1
    if args.json:
        d = to_dict(p)
        for c, cd in zip(p.capabilities, d.get("capabilities", []), strict=True):
            cd["endpoint"] = endpoint(atlas, p.id, c)
        print(json.dumps(d, indent=2))
        return 0
    print(f"id:          {p.id}")
    print(f"kind:        {KIND_NAMES.get(p.kind, p.kind)}")
    print(f"namespace:   {p.namespace}")
    print(f"state:       {STATE_NAMES.get(p.state, p.state)}" + (f" ({p.state_detail})" if p.state_detail else ""))
    print(f"heartbeat:   {age(p.last_heartbeat_ms)}")
    reg = getattr(p, "registration_id", "")
    if reg:
        print(f"registration: {reg}")
    print("capabilities:")
    for c in p.capabilities:
        print(f"  - {c.contract_id} [{TRANSPORT_NAMES.get(c.transport, c.transport)}] {endpoint(atlas, p.id, c)}"
              f"  {params_text(c.params)}".rstrip())
        if c.description:
            print(f"      {c.description}")
    if p.capability_md:
        print("CAPABILITY.md:")
        for line in p.capability_md.splitlines():
            print(f"  {line}")
    return 0
