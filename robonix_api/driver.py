"""The lifecycle Driver: a serialized state machine behind ``robonix.contracts.RobonixLifecycleDriver``.

Kept free of networking and of the atlas client so its exact replies (``ok``/``state``/``error``, the
robonix Python SDK's values) can be unit-tested; the provider plugs in the handlers and a
``push_state(state, detail)`` callback that mirrors each transition into the atlas.
"""

from __future__ import annotations

import json
import logging
import re
import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import grpc

from robonix_api import telemetry
from robonix_api.proto_gen import lifecycle_pb2, robonix_contracts_pb2_grpc
from robonix_api.result import Deferred, Err, Ok
from robonix_api.validation import ERROR_MAX
from robonix_common.finite_json import non_finite_message

log = logging.getLogger(__name__)

CMD_INIT = lifecycle_pb2.Driver_Request.CMD_INIT
CMD_ACTIVATE = lifecycle_pb2.Driver_Request.CMD_ACTIVATE
CMD_DEACTIVATE = lifecycle_pb2.Driver_Request.CMD_DEACTIVATE
CMD_SHUTDOWN = lifecycle_pb2.Driver_Request.CMD_SHUTDOWN

# Provider states (lower-case strings are what the Driver reply carries).
REGISTERED = "registered"
INACTIVE = "inactive"
ACTIVE = "active"
ERROR = "error"
TERMINATED = "terminated"
DEFERRED = "deferred"  # reply-only: never a provider state

#: command -> (verb for messages, handler slot, states it may start from, target state)
_COMMANDS: dict[int, tuple[str, str, frozenset[str], str]] = {
    CMD_INIT: ("init", "init", frozenset({REGISTERED, INACTIVE, ERROR}), INACTIVE),
    CMD_ACTIVATE: ("activate", "activate", frozenset({INACTIVE}), ACTIVE),
    CMD_DEACTIVATE: ("deactivate", "deactivate", frozenset({ACTIVE}), INACTIVE),
    CMD_SHUTDOWN: ("shutdown", "shutdown", frozenset({REGISTERED, INACTIVE, ACTIVE, ERROR}), TERMINATED),
}
_WHY_NOT = {
    REGISTERED: "not initialized",
    ERROR: "in error (send CMD_INIT again)",
    TERMINATED: "already terminated",
    ACTIVE: "active (deactivate first)",
    INACTIVE: "not active",
}

Handler = Callable[..., Any]
PushState = Callable[[str, str], None]


@dataclass(frozen=True)
class Reply:
    """A Driver reply before it becomes a ``Driver_Response``."""

    ok: bool
    state: str
    error: str = ""

    def to_proto(self) -> lifecycle_pb2.Driver_Response:
        """As the wire ``Driver_Response``, the error cut to ERROR_MAX characters."""
        error = self.error if len(self.error) <= ERROR_MAX else self.error[: ERROR_MAX - 20] + \
            f"... ({len(self.error)} chars)"  # a handler's Err may echo a huge config value
        return lifecycle_pb2.Driver_Response(ok=self.ok, state=self.state, error=error)


#: config_json is refused above this size (bytes of UTF-8) or nesting depth, before it is parsed.
CONFIG_JSON_MAX_BYTES = 1 << 20
CONFIG_JSON_MAX_DEPTH = 32
# One left-to-right pass: a string token (possessive, and an unterminated one runs to the end, so the
# scan never restarts inside it: linear on any input) or a bracket, captured.
_TOKENS = re.compile(r'"(?:[^"\\]++|\\.)*+"?|([\[\]{}])')


def json_depth(text: str) -> int:
    """Deepest ``[``/``{`` nesting of a JSON text (strings skipped), without recursion: a guard to run
    before ``json.loads``, whose C parser recurses once per level."""
    brackets = "".join(_TOKENS.findall(text))
    depth = deepest = 0
    for ch in brackets:
        if ch in "[{":
            depth += 1
            deepest = max(deepest, depth)
        else:
            depth -= 1
    return deepest


def parse_config_json(text: str) -> dict[str, Any]:
    """robonix rule: empty -> {}, valid non-object JSON -> {}, invalid JSON -> ValueError naming the spot.

    Bounded: more than :data:`CONFIG_JSON_MAX_BYTES` or nesting deeper than :data:`CONFIG_JSON_MAX_DEPTH`
    is a ValueError naming ``config_json`` (checked before parsing, so no RecursionError can escape).
    """
    if not text.strip():
        return {}
    size = len(text.encode("utf-8", "surrogatepass"))
    if size > CONFIG_JSON_MAX_BYTES:
        raise ValueError(f"config_json: at most {CONFIG_JSON_MAX_BYTES} bytes, got {size}")
    depth = json_depth(text)
    if depth > CONFIG_JSON_MAX_DEPTH:
        raise ValueError(f"config_json: nested too deeply ({depth} levels, at most {CONFIG_JSON_MAX_DEPTH})")
    try:
        value = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ValueError(f"config_json: invalid JSON at line {exc.lineno} column {exc.colno}: {exc.msg}") from None
    except RecursionError:
        raise ValueError("config_json: nested too deeply to parse") from None
    if not isinstance(value, dict):
        log.warning("config_json is a JSON %s, not an object; using {}", type(value).__name__)
        return {}
    bad = non_finite_message(value)
    if bad:
        raise ValueError(f"config_json: {bad}")
    return value


def call_handler(name: str, fn: Handler | None, *args: Any) -> Ok | Err | Deferred:
    """Run one lifecycle handler; a missing one is Ok, an exception or a wrong return type is Err."""
    if fn is None:
        return Ok()
    try:
        result = fn(*args)
    except Exception as exc:  # the handler's failure is reported, never crashes the Driver
        log.exception("on_%s raised", name)
        return Err(f"on_{name} raised {type(exc).__name__}: {exc}")
    if isinstance(result, Ok | Err | Deferred):
        return result
    return Err(
        f"TypeError: on_{name} returned {type(result).__name__}; expected Ok(), Err(msg) or Deferred(reason)"
    )


class Lifecycle:
    """Provider lifecycle state and the Driver command logic; one lock serializes every command.

    Refused commands (illegal transition, bad config_json) leave the state alone: the request was
    wrong, not the provider. A handler's ``Err`` and an unknown command move the provider to ERROR, as
    robonix's SDK does. Invalid ``config_json`` raises :class:`ValueError` out of :meth:`handle`; the gRPC
    face turns it into INVALID_ARGUMENT (robonix's SDK lets the same parse error fail the RPC too, so the
    outcome is the same: no reply body, state unchanged).
    """

    def __init__(self, push_state: PushState | None = None) -> None:
        self.handlers: dict[str, Handler | None] = {"init": None, "activate": None, "deactivate": None,
                                                     "shutdown": None}
        self._push = push_state
        self._lock = threading.Lock()
        self._state = REGISTERED
        self._detail = ""
        self.config: dict[str, Any] = {}
        self.terminated = threading.Event()

    @property
    def state(self) -> str:
        """The current lifecycle state name (registered, inactive, active, …)."""
        return self._state

    @property
    def detail(self) -> str:
        """The last reason pushed with the state (Deferred reason or error message)."""
        return self._detail

    def set_push(self, push_state: PushState | None) -> None:
        """Where state changes are reported (the provider pushes them to the atlas); None stops reporting."""
        self._push = push_state

    def handle(self, command: int, config_json: str = "") -> Reply:
        """Run one Driver command to completion (serialized with every other command)."""
        with self._lock:
            return self._handle_locked(int(command), config_json)

    def shutdown(self, why: str = "") -> Reply:
        """CMD_SHUTDOWN from inside the process (signal, stop()); a no-op once terminated."""
        with self._lock:
            if self._state == TERMINATED:
                return Reply(True, TERMINATED)
            return self._handle_locked(CMD_SHUTDOWN, "", detail=why, force=True)

    def _handle_locked(self, command: int, config_json: str, detail: str = "", force: bool = False) -> Reply:
        entry = _COMMANDS.get(command)
        if entry is None:  # robonix's SDK moves the provider to ERROR here too (a newer caller than us)
            known = ", ".join(f"{n}={c}" for c, n in ((CMD_INIT, "CMD_INIT"), (CMD_ACTIVATE, "CMD_ACTIVATE"),
                                                       (CMD_DEACTIVATE, "CMD_DEACTIVATE"),
                                                       (CMD_SHUTDOWN, "CMD_SHUTDOWN")))
            why = f"unknown command {command} (field command; expected {known})"
            if self._state != TERMINATED:
                self._move(ERROR, why)
            return Reply(False, ERROR, why)
        verb, slot, allowed, target = entry
        if self._state == target and command != CMD_INIT:
            return Reply(True, target)  # idempotent repeat (activate twice, shutdown twice)
        if self._state not in allowed:
            why = _WHY_NOT.get(self._state, "not allowed")
            return Reply(False, ERROR, f"cannot {verb}: {why} (state {self._state})")
        args: tuple[Any, ...] = ()
        if command == CMD_INIT:
            cfg = parse_config_json(config_json)  # ValueError: the RPC fails, the state stays (as in robonix)
            args = (cfg,)
        result = call_handler(slot, self.handlers.get(slot), *args)
        if isinstance(result, Deferred) and force:  # a signal cannot be postponed
            result = Err(f"on_{slot} deferred: {result.reason}")
        if isinstance(result, Deferred):
            self._detail = result.reason
            self._notify(self._state, result.reason)
            return Reply(False, DEFERRED, result.reason)
        if command == CMD_SHUTDOWN:  # shutdown always ends the provider, even if on_shutdown failed
            self._move(TERMINATED, detail or (result.msg if isinstance(result, Err) else ""))
            self.terminated.set()
            return Reply(True, TERMINATED) if isinstance(result, Ok) else Reply(False, ERROR, result.msg)
        if isinstance(result, Err):
            self._move(ERROR, result.msg)
            return Reply(False, ERROR, result.msg)
        if command == CMD_INIT:
            self.config = args[0]
        self._move(target, "")
        return Reply(True, target)

    def _move(self, state: str, detail: str) -> None:
        self._state, self._detail = state, detail
        self._notify(state, detail)

    def _notify(self, state: str, detail: str) -> None:
        if self._push is None:
            return
        try:
            self._push(state, detail)
        except Exception as exc:  # the atlas being away must not fail the Driver reply
            log.warning("could not push state %s to atlas: %s", state, exc)


class DriverServicer(robonix_contracts_pb2_grpc.RobonixLifecycleDriverServicer):
    """gRPC face of :class:`Lifecycle` (``/robonix.contracts.RobonixLifecycleDriver/Driver``)."""

    def __init__(self, lifecycle: Lifecycle) -> None:
        self._lifecycle = lifecycle

    def Driver(self, request: lifecycle_pb2.Driver_Request, context: Any) -> lifecycle_pb2.Driver_Response:
        """The gRPC Driver call: run the command (in a trace span when tracing is on) and reply."""
        tracer = telemetry.tracer()
        if tracer is None:
            return self._drive(request, context)
        verb = _COMMANDS.get(int(request.command), (str(request.command),))[0]
        with tracer.start_as_current_span(f"lifecycle.{verb}", context=telemetry.context_from_grpc(context)) as span:
            span.set_attribute("lifecycle.from_state", self._lifecycle.state)
            reply = self._drive(request, context)
            telemetry.set_attributes(span, (("lifecycle.ok", reply.ok), ("lifecycle.state", reply.state),
                                            ("lifecycle.error", reply.error or None)))
            return reply

    def _drive(self, request: lifecycle_pb2.Driver_Request, context: Any) -> lifecycle_pb2.Driver_Response:
        try:
            reply = self._lifecycle.handle(request.command, request.config_json)
        except ValueError as exc:  # malformed config_json: fail the RPC, naming the field
            log.warning("Driver(command=%d) refused: %s", request.command, exc)
            context.abort(grpc.StatusCode.INVALID_ARGUMENT, str(exc)[:512])
        log.info("Driver(command=%d) -> ok=%s state=%s %s", request.command, reply.ok, reply.state, reply.error)
        return reply.to_proto()


def pascal(contract_id: str) -> str:
    """robonix-api's contract -> service name rule: ``robonix/service/map/driver`` -> ``RobonixServiceMapDriver``."""
    return "".join(part.capitalize() for seg in contract_id.strip("/").split("/") for part in seg.split("_") if part)


def namespace_driver_contract(namespace: str) -> str:
    """The per-namespace driver contract robonix-api providers declare (``<namespace>/driver``)."""
    return f"{namespace.strip('/')}/driver"


def namespace_driver_services(namespace: str) -> tuple[str, ...]:
    """gRPC service names under which robonix callers look for a namespace's Driver.

    robonix-api 0.1.0rc1 names it after the whole contract id (``RobonixServiceNavigationDriver``);
    robonix's ``rbnx boot`` strips the leading ``robonix/`` (``ServiceNavigationDriver``). Both are served.
    """
    contract = namespace_driver_contract(namespace)
    names = [pascal(contract)]
    if contract.startswith("robonix/"):
        names.append(pascal(contract.removeprefix("robonix/")))
    return tuple(dict.fromkeys(names))


def add_namespace_driver(lifecycle: Lifecycle, namespace: str, server: grpc.Server) -> str:
    """Serve the same Driver under the namespace's service names; returns the primary service name."""
    servicer = DriverServicer(lifecycle)
    handlers = {"Driver": grpc.unary_unary_rpc_method_handler(
        servicer.Driver, request_deserializer=lifecycle_pb2.Driver_Request.FromString,
        response_serializer=lifecycle_pb2.Driver_Response.SerializeToString)}
    names = namespace_driver_services(namespace)
    for name in names:
        if name == "RobonixLifecycleDriver":
            continue  # already served by the generated servicer
        server.add_generic_rpc_handlers((grpc.method_handlers_generic_handler(f"robonix.contracts.{name}", handlers),))
    return names[0]
