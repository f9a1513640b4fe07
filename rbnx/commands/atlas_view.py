"""How the read-only atlas commands (caps, contracts, describe, tools, channels, inspect) show things:
protobuf as dicts, plain tables, heartbeat ages and capability endpoints."""

from __future__ import annotations

import time
from typing import Any

from google.protobuf.json_format import MessageToDict

from rbnx.atlas_rpc import TRANSPORT_NAMES, Atlas, AtlasError
from robonix_api.proto_gen import atlas_pb2


def to_dict(msg: Any) -> dict[str, Any]:
    """A protobuf message as a JSON-ready dict with the proto field names and every field present."""
    return MessageToDict(msg, preserving_proto_field_name=True, always_print_fields_with_no_presence=True)


def table(rows: list[list[str]], header: list[str]) -> list[str]:
    """Rows as left-aligned columns under ``header`` (plain text, no borders)."""
    widths = [max(len(h), *(len(r[i]) for r in rows)) if rows else len(h) for i, h in enumerate(header)]
    fmt = "  ".join(f"{{:<{w}}}" for w in widths)
    return [fmt.format(*header).rstrip(), *(fmt.format(*r).rstrip() for r in rows)]


def age(ms: int) -> str:
    """How long ago a millisecond epoch stamp was, e.g. ``3.2s ago`` (``-`` for never)."""
    if not ms:
        return "-"
    return f"{max(0.0, time.time() - ms / 1000):.1f}s ago"


_INSPECT_CACHE: dict[str, dict[tuple[str, str, str], str]] = {}


def inspect_endpoints(atlas: Atlas) -> dict[tuple[str, str, str], str]:
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


def endpoint(atlas: Atlas, pid: str, cap: atlas_pb2.Capability) -> str:
    """From InspectAtlas when it lists it; otherwise open and close a channel to learn it."""
    label = TRANSPORT_NAMES.get(cap.transport, str(cap.transport))
    known = inspect_endpoints(atlas).get((pid, cap.contract_id, label))
    if known:
        return known
    try:
        return atlas.endpoint(pid, cap.contract_id, cap.transport)[0]
    except AtlasError as exc:
        return f"? ({exc})"
