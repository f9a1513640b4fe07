"""`rbnx tools`: the MCP tools declared at the atlas, and the deployment's gateway."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from rbnx.atlas_rpc import Atlas
from rbnx.boot.statefile import gateways
from rbnx.commands.atlas_view import endpoint, table
from robonix_api.proto_gen import atlas_pb2


def register(sub: Any) -> None:
    """``tools`` and its options."""
    t = sub.add_parser("tools", help="MCP tools (mcp-transport capabilities)")
    t.add_argument("--json", action="store_true")
    t.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Connect to ``--atlas`` and print its MCP tools."""
    with Atlas(args.atlas) as atlas:
        return show(args, atlas)


def show(args: argparse.Namespace, atlas: Atlas) -> int:
    """Print every MCP tool (and the deployment's gateway first) as a table or ``--json``."""
    rows, out = [], []
    for p in sorted(atlas.query(transport=atlas_pb2.TRANSPORT_MCP), key=lambda p: p.id):
        for c in p.capabilities:
            if c.transport != atlas_pb2.TRANSPORT_MCP:
                continue
            ep = endpoint(atlas, p.id, c)
            tool = c.contract_id.rsplit("/", 1)[-1]
            rows.append([tool, p.id, c.contract_id, ep, c.description])
            out.append({"tool": tool, "provider": p.id, "contract_id": c.contract_id, "endpoint": ep,
                        "description": c.description, "input_schema_json": c.params.mcp.input_schema_json})
    for gw in gateways(atlas.addr):  # the deployment's one endpoint: every tool above + lifecycle tools
        rows.insert(0, ["*", "gateway", Path(gw["deploy"]).name, gw["url"], "all tools as <entry>.<tool> + lifecycle"])
        out.insert(0, {"tool": "*", "provider": "gateway", "contract_id": "", "endpoint": gw["url"],
                       "deploy": gw["deploy"], "description": "MCP gateway of the deployment"})
    if args.json:
        print(json.dumps(out, indent=2))
    elif not rows:
        print("no MCP tools declared")
    else:
        for line in table(rows, ["TOOL", "PROVIDER", "CONTRACT", "ENDPOINT", "DESCRIPTION"]):
            print(line)
    return 0
