"""The atlas gRPC server (``robonix.atlas.Atlas``) and the ``robonix-atlas`` console script.

The servicer is deliberately thin: it converts messages and maps ``RegistryError`` to a gRPC status;
every rule lives in ``atlas.registry``. A background reaper thread runs the heartbeat eviction.
"""

from __future__ import annotations

import argparse
import json
import logging
import signal
import socket
import sys
import threading
from concurrent import futures
from pathlib import Path
from typing import Any

import grpc

from atlas import settings
from atlas.catalogue import Catalogue
from atlas.registry import Registry, RegistryError
from atlas.trust import Trust, parse_allowed_hosts
from robonix_api import auth
from robonix_api.proto_gen import atlas_pb2, atlas_pb2_grpc
from robonix_api.types import Kind, params_from_pb, params_to_pb

log = logging.getLogger("atlas")
#: Register answers carry the new registration's id in this trailing metadata (robonix's RegisterResponse
#: has only ``id``); our SDK sends it back on Heartbeat to learn when its id was taken over.
REGISTRATION_ID_KEY = "robonix-registration-id"

DEFAULT_LISTEN = settings.DEFAULT_LISTEN


class AtlasServicer(atlas_pb2_grpc.AtlasServicer):
    """Message <-> registry translation, plus the token check of :class:`atlas.trust.Trust`."""

    def __init__(self, registry: Registry, trust: Trust | None = None) -> None:
        self.registry = registry
        self.trust = trust or Trust()

    def _guard(self, context: grpc.ServicerContext, rpc: str) -> None:
        bad = self.trust.refusal(rpc, context.invocation_metadata())
        if bad is not None:
            log.warning("%s refused from %s: %s", rpc, context.peer(), bad[0])
            context.abort(getattr(grpc.StatusCode, bad[0]), bad[1])

    @staticmethod
    def _run(context: grpc.ServicerContext, fn: Any, *args: Any, **kwargs: Any) -> Any:
        try:
            return fn(*args, **kwargs)
        except RegistryError as exc:
            context.abort(getattr(grpc.StatusCode, exc.code, grpc.StatusCode.UNKNOWN), exc.message)

    def _register(self, kind: Kind, req: Any, context: grpc.ServicerContext, rpc: str) -> Any:
        self._guard(context, rpc)
        pid, reg_id = self._run(
            context,
            self.registry.register_ex,
            kind,
            req.id,
            req.namespace,
            req.capability_md_path,
            req.capability_md,
            may_replace_live=self.trust.holds_token(context.invocation_metadata()),
        )
        context.set_trailing_metadata(((REGISTRATION_ID_KEY, reg_id),))
        return atlas_pb2.RegisterResponse(id=pid)

    def RegisterPrimitive(self, request: Any, context: grpc.ServicerContext) -> Any:
        return self._register(Kind.PRIMITIVE, request, context, "RegisterPrimitive")

    def RegisterService(self, request: Any, context: grpc.ServicerContext) -> Any:
        return self._register(Kind.SERVICE, request, context, "RegisterService")

    def RegisterSkill(self, request: Any, context: grpc.ServicerContext) -> Any:
        return self._register(Kind.SKILL, request, context, "RegisterSkill")

    def Unregister(self, request: Any, context: grpc.ServicerContext) -> Any:
        self._guard(context, "Unregister")
        return atlas_pb2.UnregisterResponse(
            was_present=self._run(context, self.registry.unregister, request.id)
        )

    def Heartbeat(self, request: Any, context: grpc.ServicerContext) -> Any:
        self._guard(context, "Heartbeat")
        reg_id = next((str(v) for k, v in context.invocation_metadata() or () if k == REGISTRATION_ID_KEY), "")
        self._run(context, self.registry.heartbeat, request.id, reg_id)
        return atlas_pb2.HeartbeatResponse()

    def SetLifecycleState(self, request: Any, context: grpc.ServicerContext) -> Any:
        self._guard(context, "SetLifecycleState")
        prev = self._run(context, self.registry.set_state, request.id, request.state, request.detail)
        return atlas_pb2.SetLifecycleStateResponse(previous_state=int(prev))

    def DeclareCapability(self, request: Any, context: grpc.ServicerContext) -> Any:
        self._guard(context, "DeclareCapability")
        params = params_from_pb(request.params) if request.HasField("params") else None
        ep = self._run(
            context,
            self.registry.declare,
            request.provider_id,
            request.contract_id,
            request.transport,
            request.endpoint,
            params,
            request.description,
        )
        return atlas_pb2.DeclareCapabilityResponse(endpoint=ep)

    def Query(self, request: Any, context: grpc.ServicerContext) -> Any:
        providers = self._run(
            context,
            self.registry.query,
            request.kind,
            request.id,
            request.contract_id,
            request.transport,
            request.namespace_prefix,
        )
        resp = atlas_pb2.QueryResponse()
        for p in providers:
            p.to_pb(resp.providers.add())
        return resp

    def ConnectCapability(self, request: Any, context: grpc.ServicerContext) -> Any:
        self._guard(context, "ConnectCapability")
        ch = self._run(
            context,
            self.registry.connect,
            request.consumer_id,
            request.provider_id,
            request.contract_id,
            request.transport,
        )
        resp = atlas_pb2.ConnectCapabilityResponse(channel_id=ch.channel_id, endpoint=ch.endpoint)
        resp.params.SetInParent()  # robonix: params is always present
        params_to_pb(ch.params, resp.params)
        return resp

    def DisconnectCapability(self, request: Any, context: grpc.ServicerContext) -> Any:
        self._guard(context, "DisconnectCapability")
        return atlas_pb2.DisconnectCapabilityResponse(
            was_open=self._run(context, self.registry.disconnect, request.channel_id)
        )

    def QueryContract(self, request: Any, context: grpc.ServicerContext) -> Any:
        desc = self._run(context, self.registry.query_contract, request.contract_id)
        resp = atlas_pb2.QueryContractResponse(found=desc is not None)
        if desc is None:
            resp.contract.SetInParent()  # robonix: present but defaulted
        else:
            desc.to_pb(resp.contract)
        return resp

    def ListContracts(self, request: Any, context: grpc.ServicerContext) -> Any:
        resp = atlas_pb2.ListContractsResponse()
        for desc in self._run(context, self.registry.list_contracts, request.namespace_prefix):
            desc.to_pb(resp.contracts.add())
        return resp

    def InspectAtlas(self, request: Any, context: grpc.ServicerContext) -> Any:
        return atlas_pb2.InspectAtlasResponse(json=json.dumps(self.registry.snapshot(), sort_keys=True))


def parse_listen(listen: str) -> tuple[str, int]:
    """``host:port`` (IPv6 as ``[::1]:port``) -> (host, port); ValueError naming ``listen`` otherwise."""
    host, sep, port_s = listen.strip().rpartition(":")
    if not sep or not host or not port_s.isdigit() or not 0 <= int(port_s) <= 65535:
        raise ValueError(f"listen: expected HOST:PORT (port 0-65535), got {listen!r}")
    return host, int(port_s)


def _probe_bind(host: str, port: int) -> None:
    """Fail early with one clear OSError (gRPC's own bind failure also spams its C-core log)."""
    bare = host[1:-1] if host.startswith("[") and host.endswith("]") else host
    try:
        infos = socket.getaddrinfo(bare, port, type=socket.SOCK_STREAM)
    except OSError as exc:
        raise OSError(f"listen: cannot resolve {host!r} ({exc})") from None
    family, kind, proto, _, addr = infos[0]
    with socket.socket(family, kind, proto) as sock:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            sock.bind(addr)
        except OSError as exc:
            raise OSError(f"listen: cannot bind {host}:{port} ({exc.strerror or exc})") from None


class AtlasServer:
    """An atlas on one address, in-process. ``start()`` returns the bound ``HOST:PORT``."""

    def __init__(
        self,
        listen: str = DEFAULT_LISTEN,
        catalogue_roots: list[Path] | None = None,
        heartbeat_timeout_ms: int = 90000,
        eviction_interval_ms: int = 10000,
        gc_after_terminated_ms: int = 600000,
        token: str = "",
        allowed_hosts: tuple[str, ...] | list[str] | str | None = None,
        **registry_options: Any,
    ) -> None:
        """``token`` "" = no authentication (robonix's atlas); ``allowed_hosts`` adds hosts beyond
        loopback that gRPC/MCP endpoints may name ("*" = any). ``registry_options`` go to
        :class:`atlas.registry.Registry` (channel lease and caps)."""
        self.listen = listen
        self.eviction_interval_ms = int(eviction_interval_ms)
        self.trust = Trust(token=token or "", allowed_hosts=parse_allowed_hosts(allowed_hosts))
        self.registry = Registry(
            Catalogue.load([Path(r) for r in catalogue_roots] if catalogue_roots else None),
            heartbeat_timeout_ms=heartbeat_timeout_ms,
            gc_after_terminated_ms=gc_after_terminated_ms,
            endpoint_check=self.trust.endpoint_problem,
            **registry_options,
        )
        self._server: grpc.Server | None = None
        self._address = ""
        self._stop = threading.Event()
        self._reaper: threading.Thread | None = None

    @property
    def address(self) -> str:
        """The bound ``HOST:PORT`` ("" before start)."""
        return self._address

    def start(self) -> str:
        """Bind and serve. Raises ValueError for a malformed address, OSError when it cannot bind."""
        if self._server is not None:
            return self._address
        host, port = parse_listen(self.listen)
        if port:
            _probe_bind(host, port)
        server = grpc.server(
            futures.ThreadPoolExecutor(max_workers=16, thread_name_prefix="atlas"),
            # Without this, gRPC sets SO_REUSEPORT and a second atlas would share a busy port silently.
            options=[("grpc.so_reuseport", 0)],
        )
        atlas_pb2_grpc.add_AtlasServicer_to_server(AtlasServicer(self.registry, self.trust), server)
        try:
            bound = server.add_insecure_port(f"{host}:{port}")
        except RuntimeError as exc:
            raise OSError(f"listen: cannot bind {self.listen} ({exc})") from None
        if not bound:
            raise OSError(f"listen: cannot bind {self.listen} (address in use or not local)")
        server.start()
        self._server = server
        self._address = f"{host}:{bound}"
        self._stop.clear()
        if self.eviction_interval_ms > 0:  # heartbeat eviction (when enabled) and channel leases
            self._reaper = threading.Thread(target=self._reap, name="atlas-reaper", daemon=True)
            self._reaper.start()
        log.info(
            "atlas serving on %s (%d contracts, heartbeat timeout %d ms, eviction every %d ms, %s)",
            self._address,
            len(self.registry.catalogue),
            self.registry.heartbeat_timeout_ms,
            self.eviction_interval_ms,
            "deployment token required for changes" if self.trust.token else "no authentication",
        )
        return self._address

    def _reap(self) -> None:
        while not self._stop.wait(self.eviction_interval_ms / 1000.0):
            try:
                self.registry.sweep()
            except Exception:  # the reaper must survive anything
                log.exception("eviction sweep failed")

    def stop(self, grace: float | None = None) -> None:
        """Stop serving (in-flight RPCs get ``grace`` seconds) and join the reaper."""
        self._stop.set()
        server, self._server = self._server, None
        if server is not None:
            server.stop(grace).wait()
        if self._reaper is not None:
            self._reaper.join(timeout=5)
            self._reaper = None

    def __enter__(self) -> AtlasServer:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop(0)


def main(argv: list[str] | None = None) -> int:
    """Console script: serve until SIGTERM/SIGINT (exit 0); bad arguments or a busy port exit 2."""
    ap = argparse.ArgumentParser(prog="robonix-atlas", description="robonix atlas registry (gRPC)")
    ap.add_argument(
        "--listen", default=None, help=f"HOST:PORT (env ROBONIX_ATLAS_LISTEN, default {DEFAULT_LISTEN})"
    )
    ap.add_argument(
        "--capabilities", default=None, help="comma-separated contract roots (env ROBONIX_ATLAS_CAPABILITIES)"
    )
    ap.add_argument(
        "--heartbeat-timeout-ms", type=int, default=None, help="0 disables eviction (default 90000)"
    )
    ap.add_argument("--eviction-interval-ms", type=int, default=None, help="default 10000")
    ap.add_argument("--gc-after-terminated-ms", type=int, default=None, help="default 600000")
    ap.add_argument("--log-level", default=None, help="env ROBONIX_LOG_LEVEL, default INFO")
    ap.add_argument("--allowed-hosts", default=None, metavar="H1,H2",
                    help="hosts besides loopback that gRPC/MCP endpoints may name, '*' for any "
                         "(env ROBONIX_ATLAS_ALLOWED_HOSTS)")
    ap.add_argument(
        "--config-json", default=None, metavar="JSON",
        help='settings as one JSON object, as robonix\'s rbnx passes system.atlas: {"listen": ..., "log": ...}; '
        "explicit flags win",
    )
    a = ap.parse_args(argv)
    try:
        cfg = settings.resolve(
            {"listen": a.listen, "capabilities": a.capabilities, "heartbeat_timeout_ms": a.heartbeat_timeout_ms,
             "eviction_interval_ms": a.eviction_interval_ms, "gc_after_terminated_ms": a.gc_after_terminated_ms,
             "log_level": a.log_level, "allowed_hosts": a.allowed_hosts},
            a.config_json,
        )
    except ValueError as exc:
        print(f"robonix-atlas: {exc}", file=sys.stderr, flush=True)
        return 2
    logging.basicConfig(
        level=getattr(logging, cfg.log_level.upper(), logging.INFO),
        stream=sys.stderr,
        format="%(asctime)s %(levelname)s %(name)s: %(message)s",
    )
    if cfg.ignored_keys:
        log.warning("--config-json: ignoring unknown keys %s", ", ".join(cfg.ignored_keys))
    log.debug("settings: %s", cfg)
    try:
        server = AtlasServer(
            listen=cfg.listen,
            catalogue_roots=cfg.catalogue_roots,
            heartbeat_timeout_ms=cfg.heartbeat_timeout_ms,
            eviction_interval_ms=cfg.eviction_interval_ms,
            gc_after_terminated_ms=cfg.gc_after_terminated_ms,
            token=auth.current_token() if cfg.auth != "none" else "",
            allowed_hosts=cfg.allowed_hosts,
        )
        address = server.start()
    except (ValueError, OSError) as exc:
        print(f"robonix-atlas: {exc}", file=sys.stderr, flush=True)
        return 2

    stop = threading.Event()

    def _on_signal(signum: int, _frame: object) -> None:
        log.info("signal %d: stopping", signum)
        stop.set()

    signal.signal(signal.SIGTERM, _on_signal)
    signal.signal(signal.SIGINT, _on_signal)
    print(f"atlas listening on {address}", flush=True)
    while not stop.wait(0.5):
        pass
    server.stop(grace=1.0)
    log.info("atlas stopped")
    return 0


if __name__ == "__main__":
    sys.exit(main())
