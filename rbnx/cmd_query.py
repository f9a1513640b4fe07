"""Read-only atlas commands: caps, contracts, describe, tools, channels, inspect."""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

from google.protobuf.json_format import MessageToDict

from rbnx.atlas_rpc import KIND_NAMES, STATE_NAMES, TRANSPORT_NAMES, Atlas, AtlasError, params_text
from rbnx.statefile import restarts_for_atlas
from robonix_api.proto_gen import atlas_pb2


def _to_dict(msg: Any) -> dict[str, Any]:
    return MessageToDict(msg, preserving_proto_field_name=True, always_print_fields_with_no_presence=True)


def _table(rows: list[list[str]], header: list[str]) -> list[str]:
    widths = [max(len(h), *(len(r[i]) for r in rows)) if rows else len(h) for i, h in enumerate(header)]
    fmt = "  ".join(f"{{:<{w}}}" for w in widths)
    return [fmt.format(*header).rstrip(), *(fmt.format(*r).rstrip() for r in rows)]


def _age(ms: int) -> str:
    if not ms:
        return "-"
    return f"{max(0.0, time.time() - ms / 1000):.1f}s ago"


_INSPECT_CACHE: dict[str, dict[tuple[str, str, str], str]] = {}


def _inspect_endpoints(atlas: Atlas) -> dict[tuple[str, str, str], str]:
    """Endpoints as InspectAtlas lists them (read-only, unlike opening a channel); cached per command."""
    if atlas.addr not in _INSPECT_CACHE:
        table: dict[tuple[str, str, str], str] = {}
        try:
            data = atlas.inspect()
        except AtlasError:
            data = {}
        for c in data.get("capabilities", []) if isinstance(data, dict) else []:
            if isinstance(c, dict) and c.get("endpoint"):
                table[(str(c.get("provider_id")), str(c.get("contract_id")), str(c.get("transport")).lower())] = \
                    str(c["endpoint"])
        _INSPECT_CACHE[atlas.addr] = table
    return _INSPECT_CACHE[atlas.addr]


def _endpoint(atlas: Atlas, pid: str, cap: atlas_pb2.Capability) -> str:
    """From InspectAtlas when it lists it; otherwise open and close a channel to learn it."""
    label = TRANSPORT_NAMES.get(cap.transport, str(cap.transport))
    known = _inspect_endpoints(atlas).get((pid, cap.contract_id, label))
    if known:
        return known
    try:
        return atlas.endpoint(pid, cap.contract_id, cap.transport)[0]
    except AtlasError as exc:
        return f"? ({exc})"


def cmd_caps(args: argparse.Namespace, atlas: Atlas) -> int:
    kind = {"primitive": 1, "service": 2, "skill": 3}.get(args.kind or "", 0)
    provs = sorted(atlas.query(kind=kind, id=args.id or ""), key=lambda p: p.id)
    restarts = restarts_for_atlas(atlas.addr)
    if args.json:
        out = []
        for p in provs:
            d = _to_dict(p)
            if args.verbose:
                for c, cd in zip(p.capabilities, d.get("capabilities", []), strict=True):
                    cd["endpoint"] = _endpoint(atlas, p.id, c)
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
              + (f"  heartbeat {_age(p.last_heartbeat_ms)}" if args.verbose else ""))
        for c in sorted(p.capabilities, key=lambda c: (c.contract_id, c.transport)):
            line = f"    {c.contract_id:<44} {TRANSPORT_NAMES.get(c.transport, c.transport):<5}"
            if args.verbose:
                line += f" {_endpoint(atlas, p.id, c)}  {params_text(c.params)}  {c.description}"
            print(line.rstrip())
    return 0


def cmd_contracts(args: argparse.Namespace, atlas: Atlas) -> int:
    cs = atlas.list_contracts(args.prefix or "")
    if args.json:
        print(json.dumps([_to_dict(c) for c in cs], indent=2))
        return 0
    rows = [[c.id, KIND_NAMES.get(c.kind, str(c.kind)), c.mode, c.io_srv_type or c.io_msg_type, c.description]
            for c in cs]
    for line in _table(rows, ["CONTRACT", "KIND", "MODE", "TYPE", "DESCRIPTION"]):
        print(line)
    return 0


def cmd_describe(args: argparse.Namespace, atlas: Atlas) -> int:
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
        d = _to_dict(p)
        for c, cd in zip(p.capabilities, d.get("capabilities", []), strict=True):
            cd["endpoint"] = _endpoint(atlas, p.id, c)
        print(json.dumps(d, indent=2))
        return 0
    print(f"id:          {p.id}")
    print(f"kind:        {KIND_NAMES.get(p.kind, p.kind)}")
    print(f"namespace:   {p.namespace}")
    print(f"state:       {STATE_NAMES.get(p.state, p.state)}" + (f" ({p.state_detail})" if p.state_detail else ""))
    print(f"heartbeat:   {_age(p.last_heartbeat_ms)}")
    reg = getattr(p, "registration_id", "")
    if reg:
        print(f"registration: {reg}")
    print("capabilities:")
    for c in p.capabilities:
        print(f"  - {c.contract_id} [{TRANSPORT_NAMES.get(c.transport, c.transport)}] {_endpoint(atlas, p.id, c)}"
              f"  {params_text(c.params)}".rstrip())
        if c.description:
            print(f"      {c.description}")
    if p.capability_md:
        print("CAPABILITY.md:")
        for line in p.capability_md.splitlines():
            print(f"  {line}")
    return 0


def cmd_tools(args: argparse.Namespace, atlas: Atlas) -> int:
    rows, out = [], []
    for p in sorted(atlas.query(transport=atlas_pb2.TRANSPORT_MCP), key=lambda p: p.id):
        for c in p.capabilities:
            if c.transport != atlas_pb2.TRANSPORT_MCP:
                continue
            ep = _endpoint(atlas, p.id, c)
            tool = c.contract_id.rsplit("/", 1)[-1]
            rows.append([tool, p.id, c.contract_id, ep, c.description])
            out.append({"tool": tool, "provider": p.id, "contract_id": c.contract_id, "endpoint": ep,
                        "description": c.description, "input_schema_json": c.params.mcp.input_schema_json})
    from rbnx.cmd_agents import gateways

    for gw in gateways(atlas.addr):  # the deployment's one endpoint: every tool above + lifecycle tools
        rows.insert(0, ["*", "gateway", Path(gw["deploy"]).name, gw["url"], "all tools as <entry>.<tool> + lifecycle"])
        out.insert(0, {"tool": "*", "provider": "gateway", "contract_id": "", "endpoint": gw["url"],
                       "deploy": gw["deploy"], "description": "MCP gateway of the deployment"})
    if args.json:
        print(json.dumps(out, indent=2))
    elif not rows:
        print("no MCP tools declared")
    else:
        for line in _table(rows, ["TOOL", "PROVIDER", "CONTRACT", "ENDPOINT", "DESCRIPTION"]):
            print(line)
    return 0


def cmd_channels(args: argparse.Namespace, atlas: Atlas) -> int:
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
    for line in _table(rows, [k.upper() for k in keys]):
        print(line)
    return 0


def cmd_inspect(args: argparse.Namespace, atlas: Atlas) -> int:
    print(json.dumps(atlas.inspect(), indent=2, sort_keys=True))
    return 0
