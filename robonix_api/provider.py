"""``Primitive`` / ``Service`` / ``Skill``: what a package author instantiates (robonix SDK names).

A provider registers with the atlas, serves its lifecycle Driver and contract handlers over one gRPC
server (plus MCP tools over streamable HTTP), heartbeats, and re-registers by itself when the atlas
restarts. ``run()`` blocks until CMD_SHUTDOWN or SIGTERM/SIGINT and always tears down cleanly.
"""

from __future__ import annotations

import logging
import os
import signal
import socket
import subprocess
import threading
import time
from collections.abc import Callable, Sequence
from concurrent import futures
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeVar

import grpc

from robonix_api import auth, netutil, pkg
from robonix_api.contracts import ContractSpec, builtin_contract
from robonix_api.driver import DriverServicer, Lifecycle, add_namespace_driver, namespace_driver_contract
from robonix_api.grpc_contracts import add_servicer, build_servicer, generated_servicer
from robonix_api.procs import ProcessGroups
from robonix_api.proto_gen import robonix_contracts_pb2_grpc
from robonix_api.provider_compat import RobonixProviderMixin, check_namespace
from robonix_api.topics import TopicsMixin
from robonix_api.types import GrpcParams, Kind, LifecycleState, McpParams, Ros2Params, Transport

log = logging.getLogger("robonix_api.provider")

DRIVER_CONTRACT = "robonix/lifecycle/driver"
DEFAULT_HEARTBEAT_S = 30.0
REGISTER_WAIT_S = 30.0  # how long run() waits for an atlas that is not up yet
F = TypeVar("F", bound=Callable[..., Any])


def heartbeat_period() -> float:
    """``ROBONIX_HEARTBEAT_PERIOD_S`` (tests shorten it), default 30 s like robonix."""
    raw = os.environ.get("ROBONIX_HEARTBEAT_PERIOD_S", "").strip()
    try:
        value = float(raw) if raw else DEFAULT_HEARTBEAT_S
    except ValueError:
        raise ValueError(f"ROBONIX_HEARTBEAT_PERIOD_S must be a number of seconds, got {raw!r}") from None
    return value if value > 0 else DEFAULT_HEARTBEAT_S


@dataclass
class _Declared:
    """A capability as last accepted by the atlas, kept so it can be re-declared after a restart."""

    contract_id: str
    endpoint: str
    transport: Transport
    params: Any
    description: str


class _Provider(TopicsMixin, RobonixProviderMixin):
    """Common body of the three provider kinds; they differ only in the Register RPC."""

    KIND: Kind = Kind.SERVICE

    def __init__(self, id: str, namespace: str, *, pkg_root: str | os.PathLike[str] | None = None,
                 md_path: str | os.PathLike[str] | None = None, atlas: Any = None) -> None:
        self.id = pkg.resolve_id(id)
        self.namespace = check_namespace(namespace)
        root = Path(pkg_root) if pkg_root is not None else pkg.find_pkg_root(pkg.caller_file())
        self.pkg_root: Path | None = root
        if root is not None:  # the package's own robonix codegen output, importable as robonix-api makes it
            from robonix_api.codegen import ensure_proto_gen

            ensure_proto_gen(root)
        self.md_path, self.capability_md = pkg.capability_md(root, md_path)
        self._atlas_arg = atlas
        self._atlas: Any = None
        self.lifecycle = Lifecycle()
        self._grpc_handlers: dict[str, Any] = {}  # contract id -> servicer instance
        self._mcp_handlers: dict[str, tuple[Callable[..., Any], str]] = {}
        self._declared: dict[tuple[str, Transport], _Declared] = {}
        self._pending: set[tuple[str, Transport]] = set()
        self._atlas_lock = threading.RLock()
        self._registered = False
        self._procs = ProcessGroups()
        self._stop = threading.Event()
        self._hb_wake = threading.Event()  # set: heartbeat now (stop, or the atlas is back after a loss)
        self._stop_reason = ""
        self._signalled = 0  # set by the signal handler (which must take no lock), acted on by run()
        self._ready = threading.Event()
        self._done = threading.Event()
        self._run_error: BaseException | None = None
        self._thread: threading.Thread | None = None
        self._in_run = False  # run() owns teardown; after a bare start()/bootstrap(), stop() does it
        self._grpc_server: grpc.Server | None = None
        self._mcp_server: Any = None
        self._hb_thread: threading.Thread | None = None
        self.registration_replaced = 0  # how often a heartbeat found our atlas record taken over
        self.grpc_endpoint = ""
        self.mcp_url = ""
        self._grpc_descriptions: dict[str, str] = {}
        TopicsMixin.__init__(self)
        self._init_compat()

    # ------------------------------------------------------------------ decorators

    def on_init(self, fn: F) -> F:
        """``fn(cfg: dict)`` runs on CMD_INIT with the deploy's config block (one handler: a second
        ``@on_init`` is a ``RuntimeError``, as in robonix-api)."""
        if self.lifecycle.handlers.get("init") is not None:
            raise RuntimeError("on_init handler already registered")
        self.lifecycle.handlers["init"] = fn
        return fn

    def on_activate(self, fn: F) -> F:
        self.lifecycle.handlers["activate"] = fn
        return fn

    def on_deactivate(self, fn: F) -> F:
        self.lifecycle.handlers["deactivate"] = fn
        return fn

    def on_shutdown(self, fn: F) -> F:
        self.lifecycle.handlers["shutdown"] = fn
        return fn

    def grpc(self, contract_id: str, *, description: str = "") -> Callable[[F], F]:
        """Serve ``fn(req)`` or ``fn(req, ctx)`` as the contract's generated gRPC method; declared with
        ``description``, else the docstring, else the contract's description."""
        spec = builtin_contract(contract_id)

        def deco(fn: F) -> F:
            desc = description.strip() or (fn.__doc__ or "").strip()
            self.attach_grpc_servicer(contract_id, build_servicer(spec, fn), description=desc)
            return fn

        return deco

    def mcp(self, contract_id: str, *, description: str = "") -> Callable[[F], F]:
        """Expose ``fn(req) -> response`` as an MCP tool named after the contract's last segment.

        ``req`` is the contract's request proto; a contract outside the catalogue (a robonix package's
        own) is served when ``fn`` annotates its input with a robonix codegen class instead."""
        from robonix_api.tool import codegen_input_class

        spec = mcp_contract_spec(contract_id)
        if spec.mode != "rpc":
            raise ValueError(f"@mcp({contract_id!r}): only rpc contracts can be tools (mode {spec.mode})")

        def deco(fn: F) -> F:
            if not spec.idl and codegen_input_class(fn) is None:
                raise KeyError(f"unknown contract {contract_id!r}: not in the catalogue, and {fn.__name__}'s "
                               "input is not a codegen class (json_schema()/from_dict())")
            self._mcp_handlers[contract_id] = (fn, description)
            return fn

        return deco

    def attach_grpc_servicer(self, contract_id: str, servicer: Any, *, description: str = "") -> None:
        """Serve a ready-made servicer (a subclass of the generated ``<Service>Servicer``)."""
        spec = builtin_contract(contract_id)
        generated_servicer(spec)  # fail now, naming the contract, if there is no such service
        if self._grpc_server is not None:
            raise RuntimeError(f"attach_grpc_servicer({contract_id!r}) after run() started")
        self._grpc_handlers[contract_id] = servicer
        self._grpc_descriptions[contract_id] = description

    # ------------------------------------------------------------------ properties

    @property
    def state(self) -> LifecycleState:
        """Driver state as robonix-api's ``LifecycleState`` (it also equals its lower-case name, e.g.
        ``"active"``, which this SDK returned before)."""
        return LifecycleState.parse(self.lifecycle.state)

    @property
    def config(self) -> dict[str, Any]:
        """The config dict of the last successful CMD_INIT."""
        return self.lifecycle.config

    @property
    def atlas(self) -> Any:
        """The atlas client this provider talks through (created on first use)."""
        if self._atlas is None:
            from robonix_api.atlas_client import AtlasClient

            arg = self._atlas_arg
            self._atlas = arg if arg is not None and not isinstance(arg, str) else AtlasClient(arg)
        return self._atlas

    def _atlas_address(self) -> str:
        for attr in ("address", "_address", "target"):
            value = getattr(self._atlas, attr, None)
            if isinstance(value, str) and value:
                return value
        return os.environ.get("ROBONIX_ATLAS", "127.0.0.1:50051")

    # ------------------------------------------------------------------ declaring

    def declare_capability(self, contract_id: str, endpoint: str, transport: Transport | str | int,
                           params: Any = None, description: str = "") -> str:
        """Declare (and remember, for re-registration) one capability; returns the final endpoint."""
        t = Transport.parse(transport)
        with self._atlas_lock:
            final = endpoint
            if self._registered:
                final = self.atlas.declare_capability(self.id, contract_id, endpoint, t, params=params,
                                                      description=description)
            else:  # sent right after registration
                self._pending.add((contract_id, t))
            self._declared[(contract_id, t)] = _Declared(contract_id, final, t, params, description)
            return final

    def declare_ros2_topic(self, contract_id: str, topic: str, *, qos: str = "best_effort",
                           description: str = "") -> str:
        """Declare a DDS/ROS 2 topic; returns the topic the atlas settled on (it may rename on collision)."""
        return self.declare_capability(contract_id, topic, Transport.ROS2, Ros2Params(qos_profile=qos), description)

    def declare_grpc(self, contract_id: str, endpoint: str = "", service_name: str = "", method: str = "",
                     proto_file: str = "robonix_contracts.proto", description: str = "") -> str:
        """Declare a gRPC contract at ``endpoint`` (default: this provider's own gRPC server). Service and
        method default to the catalogue's names for the contract (robonix-api requires them)."""
        spec = builtin_contract(contract_id) if not (service_name and method) else None
        params = GrpcParams(proto_file=proto_file, service_name=service_name or spec.service_name,  # type: ignore[union-attr]
                            method=method or spec.method_name)  # type: ignore[union-attr]
        desc = description or self._grpc_descriptions.get(contract_id, "") or (spec.description if spec else "")
        return self.declare_capability(contract_id, endpoint or self.grpc_endpoint, Transport.GRPC, params, desc)

    def declare_mcp(self, contract_id: str, endpoint: str = "", input_schema_json: str = "{}",
                    description: str = "") -> str:
        return self.declare_capability(contract_id, endpoint or self.mcp_url, Transport.MCP,
                                       McpParams(input_schema_json=input_schema_json or "{}"), description)

    def spawn(self, argv: str | Sequence[str], *, env: dict[str, Any] | None = None,
              log: str | os.PathLike[str] | None = None, cwd: str | os.PathLike[str] | None = None,
              **popen_kwargs: Any) -> subprocess.Popen[Any]:
        """Start a helper process in its own group; teardown sends TERM, waits 5 s, then KILL.

        As in robonix-api, ``env`` is added to this process's environment, and ``log`` sends stdout and
        stderr to a file (a bare name goes under ``<pkg_root>/rbnx-build/data/``; a path as given).
        Other keywords go to ``subprocess.Popen``.
        """
        from robonix_api.spawn import open_log

        if env is not None:
            popen_kwargs["env"] = {**os.environ, **{k: str(v) for k, v in env.items()}}
        if cwd is not None:
            popen_kwargs["cwd"] = str(cwd)
        fh = open_log(log, self.pkg_root)
        if fh is not None:
            popen_kwargs.setdefault("stdout", fh)
            popen_kwargs.setdefault("stderr", fh)
        try:
            return self._procs.spawn(argv, **popen_kwargs)
        finally:
            if fh is not None:
                fh.close()  # the child holds its own descriptor

    # ------------------------------------------------------------------ atlas plumbing

    def _register(self, wait_s: float = 0.0) -> None:
        """Register; with ``wait_s``, keep retrying while the atlas is unreachable (started after us)."""
        deadline = time.monotonic() + wait_s
        while True:
            try:
                with self._atlas_lock:
                    self._register_once()
                return
            except grpc.RpcError as exc:
                if _status_code(exc) != grpc.StatusCode.UNAVAILABLE or time.monotonic() > deadline:
                    raise
                log.warning("atlas %s unreachable; retrying registration of %s", self._atlas_address(), self.id)
                if self._stop.wait(1.0):
                    raise

    def _register_once(self) -> None:
        with self._atlas_lock:
            new_id = self.atlas.register(self.KIND, self.id, self.namespace,
                                         capability_md_path=self.md_path, capability_md=self.capability_md)
            if new_id and new_id != self.id:
                log.info("atlas assigned id %s", new_id)
                self.id = new_id
            self._registered = True
            # Say REGISTERED out loud: the atlas would otherwise report INACTIVE as soon as we declare a
            # capability, which robonix's executor reads as "already initialised" (no CMD_INIT sent).
            if self.lifecycle.state == "registered":
                self._push_state(self.lifecycle.state, self.lifecycle.detail)

    def _declare_all(self, only: set[tuple[str, Transport]] | None = None) -> None:
        """Send remembered declarations (all of them, or just ``only``) to the atlas."""
        with self._atlas_lock:
            for key, d in list(self._declared.items()):
                if only is not None and key not in only:
                    continue
                final = self.atlas.declare_capability(self.id, d.contract_id, d.endpoint, d.transport,
                                                      params=d.params, description=d.description)
                if final != d.endpoint:
                    log.warning("atlas moved %s (%s) from %s to %s", d.contract_id, d.transport.label,
                                d.endpoint, final)
                self._declared[key] = _Declared(d.contract_id, final, d.transport, d.params, d.description)
            self._pending.clear()

    def push_detail(self, detail: str) -> None:
        """Show ``detail`` next to the current lifecycle state on the atlas (``rbnx boot``/``describe`` print
        it), e.g. a long warm-up; "" clears it. Best effort: an unreachable atlas is only logged."""
        with self._atlas_lock:
            if not self._registered:
                return
            try:
                self.atlas.set_state(self.id, LifecycleState.parse(self.lifecycle.state), detail)
            except Exception as exc:  # a status note must never break the caller
                log.debug("push_detail: %s", exc)

    def _push_state(self, state: str, detail: str) -> None:
        with self._atlas_lock:
            if self._registered:
                self.atlas.set_state(self.id, LifecycleState.parse(state), detail)

    def _reregister(self) -> None:
        """The atlas forgot us (restart): register, declare everything again, re-push our state."""
        log.warning("atlas does not know provider %s (restarted?); re-registering", self.id)
        with self._atlas_lock:
            self._registered = False
            self._register_once()  # pushes REGISTERED itself
            self._declare_all()
            state, detail = self.lifecycle.state, self.lifecycle.detail
            if state != "registered":
                self._push_state(state, detail)
        log.info("re-registered %s with %d capabilities, state %s", self.id, len(self._declared), state)

    def _evicted_while_alive(self) -> bool:
        """True when the atlas marked us TERMINATED (heartbeats lapsed while we stalled) but we still run.

        A heartbeat does not revive a TERMINATED record (robonix semantics), so without this check a
        provider that was merely slow would stay invisible until the atlas garbage-collects it.
        """
        if self.lifecycle.state == "terminated" or self._stop.is_set():
            return False
        found = self.atlas.query(id=self.id)
        return bool(found) and found[0].state == LifecycleState.TERMINATED

    def _watch_atlas(self) -> None:
        """Watch the connection to the atlas on a channel of its own: when it comes back after it was lost
        (an atlas restart), wake the heartbeat at once, so this provider re-registers within about a
        second instead of at its next heartbeat (seconds to tens of seconds later)."""
        addr = next((v for v in (getattr(self._atlas, a, None) for a in ("address", "_address", "target"))
                     if isinstance(v, str) and v), "")
        if not addr:
            return  # not a client of a real atlas (a test double): nothing to watch
        try:
            addr = addr.removeprefix("grpc://")
            ch = grpc.insecure_channel(addr, options=[("grpc.enable_http_proxy", 0),
                                                      ("grpc.initial_reconnect_backoff_ms", 200),
                                                      ("grpc.min_reconnect_backoff_ms", 200),
                                                      ("grpc.max_reconnect_backoff_ms", 1000)])
        except Exception as exc:
            log.debug("no atlas watch: %s", exc)
            return
        lost = threading.Event()

        def on_change(state: grpc.ChannelConnectivity) -> None:
            if state != grpc.ChannelConnectivity.READY:
                lost.set()

        ch.subscribe(on_change)
        try:
            while not self._stop.is_set():
                if not lost.wait(1.0):
                    continue
                lost.clear()
                while not self._stop.is_set():  # (re)connect; a gone atlas is retried every second
                    ready = grpc.channel_ready_future(ch)
                    try:
                        ready.result(timeout=1.0)
                        break
                    except grpc.FutureTimeoutError:
                        ready.cancel()  # unsubscribes it; a new one asks to connect again
                self._hb_wake.set()
        except Exception as exc:
            log.debug("atlas watch ended: %s", exc)
        finally:
            ch.unsubscribe(on_change)
            # gRPC's connectivity poller thread ends on its next tick (0.2 s) once nothing is subscribed;
            # closing the channel under it makes that thread die with "Channel closed!" on stderr.
            threading.Event().wait(0.5)
            ch.close()

    def _heartbeat_loop(self, period_s: float) -> None:
        threading.Thread(target=self._watch_atlas, name=f"atlas-watch-{self.id}", daemon=True).start()
        self._heartbeat_until_stopped(period_s)

    def _heartbeat_until_stopped(self, period_s: float) -> None:
        failing = False
        while not self._stop.is_set():
            # while the atlas is unreachable, try every half second: it is back (restarted) soon
            self._hb_wake.wait(min(period_s, 0.5) if failing else period_s)
            self._hb_wake.clear()
            if self._stop.is_set():
                return
            try:
                self.atlas.heartbeat(self.id)
                if failing:
                    log.info("atlas reachable again")
                failing = False
                if self._evicted_while_alive():
                    self._reregister()
            except Exception as exc:
                code = _status_code(exc)
                if code == grpc.StatusCode.FAILED_PRECONDITION:
                    # Our atlas refuses the heartbeat of a registration somebody else replaced: say so
                    # loudly and take the id back (we hold the deployment token when one is set).
                    log.error("provider %s: ITS ATLAS REGISTRATION WAS REPLACED by another Register of the same "
                              "id (%s); re-registering", self.id, exc)
                    self.registration_replaced += 1
                if code in (grpc.StatusCode.NOT_FOUND, grpc.StatusCode.FAILED_PRECONDITION):
                    try:
                        self._reregister()
                        failing = False
                    except Exception as exc2:
                        log.warning("re-registration failed (will retry): %s", exc2)
                elif not failing:
                    log.warning("heartbeat failed (atlas unreachable?): %s", exc)
                    failing = True

    # ------------------------------------------------------------------ run / stop

    def start(self) -> None:
        """Register, serve, declare and heartbeat; returns once the provider is reachable."""
        if self._grpc_server is not None:
            raise RuntimeError(f"provider {self.id} already started")
        self.lifecycle.set_push(self._push_state)
        self._register(wait_s=REGISTER_WAIT_S)
        bind = netutil.bind_host()
        host = netutil.advertise_host(bind, self._atlas_address())
        server = grpc.server(futures.ThreadPoolExecutor(max_workers=8, thread_name_prefix="rbnx-grpc"),
                             interceptors=[auth.TokenServerInterceptor(self._token_protected())])
        robonix_contracts_pb2_grpc.add_RobonixLifecycleDriverServicer_to_server(
            DriverServicer(self.lifecycle), server)
        ns_driver_service = add_namespace_driver(self.lifecycle, self.namespace, server)
        for cid, servicer in self._grpc_handlers.items():
            add_servicer(builtin_contract(cid), servicer, server)
        port = server.add_insecure_port(netutil.host_port(bind, 0))
        if not port:
            raise RuntimeError(f"cannot bind a gRPC port on {bind}")
        server.start()
        self._grpc_server = server
        self.grpc_endpoint = netutil.host_port(host, port)
        self.declare_capability(DRIVER_CONTRACT, self.grpc_endpoint, Transport.GRPC,
                                GrpcParams(proto_file="robonix_contracts.proto",
                                           service_name="RobonixLifecycleDriver", method="Driver"))
        self._declare_namespace_driver(ns_driver_service)
        for cid in self._grpc_handlers:
            self.declare_grpc(cid)
        if self._mcp_handlers:
            self._start_mcp(bind, host)
        elif self._mcp_app is not None:
            from robonix_api.tool import declare_app_tools

            self.mcp_url = f"http://{netutil.host_port(host, self._start_mcp_app(bind))}/mcp/"
            declare_app_tools(self, self._mcp_app)
        self._declare_all(only=set(self._pending))  # declared before run(), queued while unregistered
        period = heartbeat_period()
        self._hb_thread = threading.Thread(target=self._heartbeat_loop, args=(period,),
                                           name=f"heartbeat-{self.id}", daemon=True)
        self._hb_thread.start()
        log.info("provider %s (%s) up: grpc %s%s", self.id, self.KIND.label, self.grpc_endpoint,
                 f", mcp {self.mcp_url}" if self.mcp_url else "")
        self._ready.set()

    def _token_protected(self) -> Callable[[str], bool]:
        """Which gRPC methods want the deployment token (when one is set): all but read-only contracts'.

        Deny by default: the Driver, every state-changing contract and anything unknown need it."""
        open_paths = frozenset(
            f"/robonix.contracts.{spec.service_name}/{spec.method_name}"
            for spec in (builtin_contract(cid) for cid in self._grpc_handlers if auth.is_read_only(cid))
        )
        return lambda method: method not in open_paths

    def _declare_namespace_driver(self, service_name: str) -> None:
        """Also declare ``<namespace>/driver`` (robonix-api's name for the same Driver).

        robonix's own atlas allows one ``*/driver`` per provider and refuses the second with
        FAILED_PRECONDITION; there the shared ``robonix/lifecycle/driver`` alone stays declared.
        """
        contract = namespace_driver_contract(self.namespace)
        if contract == DRIVER_CONTRACT:
            return
        try:
            self.declare_capability(contract, self.grpc_endpoint, Transport.GRPC,
                                    GrpcParams(proto_file="robonix_contracts.proto", service_name=service_name,
                                               method="Driver"))
        except grpc.RpcError as exc:
            if _status_code(exc) != grpc.StatusCode.FAILED_PRECONDITION:
                raise
            log.info("atlas keeps one driver per provider; %s not declared (%s)", contract, exc.details())

    def _start_mcp(self, bind: str, host: str) -> None:
        """Listen and declare the tools now; load the MCP server stack later (robonix_api.mcp_deferred)."""
        import json

        from robonix_api.mcp_deferred import DeferredMcpServer
        from robonix_api.mcp_tools import MCP_PATH, tool_shape

        handlers = dict(self._mcp_handlers)
        shapes = {cid: tool_shape(mcp_contract_spec(cid), fn, desc) for cid, (fn, desc) in handlers.items()}

        def build(sock: socket.socket) -> Any:
            from robonix_api.mcp_server import McpTool, McpToolServer

            tools = [McpTool(mcp_contract_spec(cid), handlers[cid][0], shape.description, shape.request_cls,
                             shape.input_schema) for cid, shape in shapes.items()]
            server = McpToolServer(self.id, tools, host=bind)
            server.start(sock=sock)
            return server

        self._mcp_server = DeferredMcpServer(self.id, bind, build)
        port = self._mcp_server.start()
        self.mcp_url = f"http://{netutil.host_port(host, port)}{MCP_PATH}"
        for cid, shape in shapes.items():
            self.declare_mcp(cid, input_schema_json=json.dumps(shape.input_schema), description=shape.description)

    def run(self) -> None:
        """Serve until CMD_SHUTDOWN or SIGTERM/SIGINT (main thread), then tear down and return."""
        restore = self._install_signals()
        self._in_run = True
        try:
            try:
                self.start()
            except BaseException:
                self._ready.set()
                raise
            while not (self._stop.is_set() or self.lifecycle.terminated.is_set()):
                if self._signalled:
                    self._stop_reason = self._stop_reason or f"signal {signal.Signals(self._signalled).name}"
                    break
                self._stop.wait(0.5)
        finally:
            try:
                self._teardown()
            finally:
                for sig, handler in restore.items():
                    signal.signal(sig, handler)

    def run_in_thread(self, timeout_s: float = 60.0) -> _Provider:
        """``run()`` on a daemon thread (tests, embedding); returns once serving, raising if start failed."""

        def target() -> None:
            try:
                self.run()
            except BaseException as exc:  # surfaced to the caller of run_in_thread / stop
                self._run_error = exc
                log.exception("provider %s failed", self.id)

        self._thread = threading.Thread(target=target, name=f"provider-{self.id}", daemon=True)
        self._thread.start()
        if not self._ready.wait(timeout_s):
            raise TimeoutError(f"provider {self.id} did not start within {timeout_s} s")
        if self._run_error is not None:
            raise RuntimeError(f"provider {self.id} failed to start: {self._run_error}") from self._run_error
        return self

    def stop(self, reason: str = "stop() called", timeout_s: float = 30.0) -> None:
        """Ask ``run()`` to shut down (as on SIGTERM) and wait for it to return."""
        self._stop_reason = self._stop_reason or reason
        self._stop.set()
        if self._thread is None and not self._ready.is_set():
            return  # never started: nothing to tear down
        if not self._in_run:  # started by start()/bootstrap(): nobody else will tear down
            if not self._done.is_set():
                self._teardown()
            return
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout_s)
        self._done.wait(timeout_s)

    def wait(self, timeout_s: float | None = None) -> bool:
        """Block until ``run()`` has torn down; True if it has."""
        return self._done.wait(timeout_s)

    def _install_signals(self) -> dict[int, Any]:
        if threading.current_thread() is not threading.main_thread():
            return {}

        def on_signal(signum: int, _frame: Any) -> None:
            # No lock here: the handler runs on the main thread, which may be holding _stop's condition
            # lock inside _stop.wait() right then; _stop.set() would deadlock (a SIGTERMed provider that
            # never exits). run() sees the flag within its 0.5 s poll.
            self._signalled = signum

        return {sig: signal.signal(sig, on_signal) for sig in (signal.SIGTERM, signal.SIGINT)}

    def _teardown(self) -> None:
        """on_shutdown (unless CMD_SHUTDOWN ran it) -> TERMINATED in atlas -> stop everything."""
        try:
            if self._registered and not self.lifecycle.terminated.is_set():
                reply = self.lifecycle.shutdown(self._stop_reason)
                log.info("shutdown (%s): ok=%s %s", self._stop_reason or "requested", reply.ok, reply.error)
            self._stop.set()
            self._hb_wake.set()
            if self._hb_thread is not None:
                self._hb_thread.join(5.0)
            self._procs.kill_all(grace_s=5.0)
            self._close_channels()
            if self._mcp_server is not None:
                self._mcp_server.stop()
            if self._mcp_app_server is not None:
                self._mcp_app_server.stop()
            self.close_topics()
            if self._grpc_server is not None:
                self._grpc_server.stop(grace=1.0).wait(5.0)  # lets the CMD_SHUTDOWN reply out
            if self._atlas is not None and self._atlas is not self._atlas_arg:
                self._atlas.close()
        finally:
            self._done.set()


def mcp_contract_spec(contract_id: str) -> ContractSpec:
    """The catalogue's contract, or an rpc contract with no IDL for one a package brings itself."""
    try:
        return builtin_contract(contract_id)
    except KeyError:
        return ContractSpec(id=contract_id, version="1", kind="service", mode="rpc", idl="")


def _status_code(exc: BaseException) -> grpc.StatusCode | None:
    """gRPC status of an atlas-client error, whether raw ``RpcError`` or wrapped with ``.code``."""
    code = getattr(exc, "code", None)
    if callable(code):
        try:
            code = code()
        except Exception:
            code = None
    if isinstance(code, grpc.StatusCode):
        return code
    cause = exc.__cause__
    return _status_code(cause) if cause is not None and cause is not exc else None


class Primitive(_Provider):
    """A hardware-facing provider (RegisterPrimitive)."""

    KIND = Kind.PRIMITIVE


class Service(_Provider):
    """A long-running capability provider (RegisterService)."""

    KIND = Kind.SERVICE


class Skill(_Provider):
    """A task-level provider; ``rbnx boot`` leaves skills INACTIVE (RegisterSkill)."""

    KIND = Kind.SKILL
