"""`rbnx map-card`: fetch the dashboard map card from a map provider and write it as a PNG.

The provider is found like any consumer finds it: Query the atlas for robonix/service/map/map_card over
gRPC (``--provider`` pins one), ConnectCapability for the endpoint, call GetMapCard.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path
from typing import Any

import grpc

from rbnx.atlas_rpc import GRPC_OPTIONS, STATE_NAMES, TRANSPORT_NAMES, Atlas, AtlasError
from robonix_api import auth
from robonix_api.proto_gen import atlas_pb2, map_pb2, robonix_contracts_pb2_grpc

MAP_CARD = "robonix/service/map/map_card"


def register(sub: Any) -> None:
    """``map-card [--provider ID] [-o PNG]``."""
    mc = sub.add_parser("map-card", help="write a map provider's dashboard map card as a PNG")
    mc.add_argument("--provider", help="provider id (default: the one live map_card provider)")
    mc.add_argument("-o", "--output", default="map.png", help="PNG path (default map.png)")
    mc.add_argument("--timeout", type=float, default=30.0, help="RPC timeout in seconds")
    mc.set_defaults(run=run)


def _provider(atlas: Atlas, pin: str | None) -> str:
    live = [p for p in atlas.query(contract_id=MAP_CARD, transport=atlas_pb2.TRANSPORT_GRPC, id=pin or "")
            if p.state != atlas_pb2.STATE_TERMINATED and (not pin or p.id == pin)]
    live = [p for p in live if any(c.contract_id == MAP_CARD and TRANSPORT_NAMES.get(c.transport) == "grpc"
                                   for c in p.capabilities)]
    if not live:
        raise AtlasError(f"no live provider of {MAP_CARD}" + (f" with id {pin!r}" if pin else ""))
    if len(live) > 1:
        names = ", ".join(f"{p.id} ({STATE_NAMES.get(p.state, p.state)})" for p in live)
        raise AtlasError(f"{MAP_CARD} is offered by {names}; pick one with --provider")
    return live[0].id


def _write(path: Path, data: bytes) -> None:
    """Temp file + rename, so an existing map.png is never left half-written."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def run(args: argparse.Namespace) -> int:
    """Connect to ``--atlas`` and write the map card."""
    with Atlas(args.atlas) as atlas:
        return write_card(args, atlas)


def write_card(args: argparse.Namespace, atlas: Atlas) -> int:
    """Fetch the map card PNG from the map provider and write it atomically to ``-o``."""
    pid = _provider(atlas, args.provider)
    endpoint, _ = atlas.endpoint(pid, MAP_CARD, atlas_pb2.TRANSPORT_GRPC)
    with auth.channel(endpoint, options=GRPC_OPTIONS) as ch:
        stub = robonix_contracts_pb2_grpc.RobonixServiceMapMapCardStub(ch)
        try:
            card = stub.GetMapCard(map_pb2.GetMapCard_Request(), timeout=args.timeout)
        except grpc.RpcError as exc:
            raise AtlasError(f"{pid} GetMapCard at {endpoint}: {exc.code().name}: {exc.details()}") from None
    if not card.ok:
        print(f"rbnx map-card: {pid}: {card.detail}", file=sys.stderr)
        return 1
    out = Path(args.output)
    try:
        _write(out, card.png)
    except OSError as exc:
        print(f"rbnx map-card: cannot write {out}: {exc.strerror or exc}", file=sys.stderr)
        return 1
    robot = (f"robot ({card.robot_x:.2f}, {card.robot_y:.2f}, {card.robot_yaw:.2f})" if card.has_robot_pose
             else "robot pose unknown")
    print(f"{out}: {card.width}x{card.height} @ {card.resolution:g} m, origin ({card.origin_x:.2f}, "
          f"{card.origin_y:.2f}) in {card.frame_id or 'map'}, {robot}, from {pid}")
    return 0
