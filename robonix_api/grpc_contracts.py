"""Binding ``@svc.grpc(contract)`` handlers to the generated ``<Service>Servicer`` classes.

The servicer class is built at run time from ``robonix_contracts_pb2_grpc`` so a package author writes
one plain function per contract; errors become gRPC statuses instead of tracebacks on the wire.
"""

from __future__ import annotations

import inspect
import logging
from collections.abc import Callable
from typing import Any

import grpc
from google.protobuf.descriptor import FieldDescriptor
from google.protobuf.message import Message

from robonix_api.contracts import ContractSpec
from robonix_api.proto_gen import robonix_contracts_pb2_grpc

log = logging.getLogger(__name__)
#: A status message is cut to this length (an error must not echo unbounded input).
MESSAGE_MAX = 1024
#: Any string field of a request longer than this is refused before the handler runs (handlers cap
#: their own fields tighter: ids 64, notes 4096).
STRING_FIELD_MAX = 64 * 1024


class StatusError(Exception):
    """Raise from a contract handler to answer with a chosen gRPC status (e.g. INVALID_ARGUMENT naming
    the field); over MCP it becomes a tool error carrying the same message."""

    def __init__(self, code: grpc.StatusCode, message: str) -> None:
        if len(message) > MESSAGE_MAX:  # never overrun gRPC's metadata limit with echoed input
            message = message[: MESSAGE_MAX - 20] + f"... ({len(message)} chars)"
        super().__init__(message)
        self.code = code
        self.message = message

    def __str__(self) -> str:
        return f"{self.code.name}: {self.message}"


def wants_context(fn: Callable[..., Any]) -> bool:
    """True when the handler takes ``(req, ctx)`` rather than ``(req)``."""
    try:
        params = inspect.signature(fn).parameters.values()
    except (TypeError, ValueError):
        return False
    positional = [p for p in params if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)]
    return len(positional) >= 2 or any(p.kind == p.VAR_POSITIONAL for p in params)


def invoke(fn: Callable[..., Any], request: Any, context: Any) -> Any:
    """Call a contract handler with the arguments it asks for."""
    return fn(request, context) if wants_context(fn) else fn(request)


def generated_servicer(spec: ContractSpec) -> tuple[type, Callable[[Any, grpc.Server], None]]:
    """The generated servicer base class and its ``add_..._to_server`` function for a contract."""
    name = spec.service_name
    base = getattr(robonix_contracts_pb2_grpc, f"{name}Servicer", None)
    add = getattr(robonix_contracts_pb2_grpc, f"add_{name}Servicer_to_server", None)
    if base is None or add is None:
        raise KeyError(f"no generated gRPC service {name} for contract {spec.id!r} (regenerate the stubs?)")
    return base, add


def build_servicer(spec: ContractSpec, fn: Callable[..., Any]) -> Any:
    """An instance of a subclass of the generated servicer whose one method calls ``fn``."""
    base, _ = generated_servicer(spec)
    cid = spec.id

    def method(self: Any, request: Any, context: grpc.ServicerContext) -> Any:
        try:
            check_strings(request)
            return invoke(fn, request, context)
        except StatusError as exc:
            context.abort(exc.code, exc.message)
        except Exception as exc:
            if _is_abort(exc):  # context.abort() inside the handler: already a status
                raise
            log.exception("handler for %s raised", cid)
            context.abort(grpc.StatusCode.INTERNAL, StatusError(grpc.StatusCode.INTERNAL,
                                                                f"{cid}: {type(exc).__name__}: {exc}").message)

    cls = type(f"{spec.service_name}Handler", (base,), {spec.method_name: method})
    return cls()


def check_strings(request: Any, limit: int = STRING_FIELD_MAX, prefix: str = "", depth: int = 0) -> None:
    """StatusError(INVALID_ARGUMENT) naming the first string field (nested messages too) over ``limit``."""
    if not isinstance(request, Message) or depth > 8:
        return
    for field, value in request.ListFields():
        name = prefix + field.name
        items = value if field.is_repeated else [value]
        if field.type == FieldDescriptor.TYPE_STRING:
            for v in items:
                if len(v) > limit:
                    raise StatusError(grpc.StatusCode.INVALID_ARGUMENT, f"{name}: at most {limit} characters, "
                                                                        f"got {len(v)}")
        elif field.type == FieldDescriptor.TYPE_MESSAGE and not field.message_type.GetOptions().map_entry:
            for v in items:
                check_strings(v, limit, name + ".", depth + 1)


def _is_abort(exc: Exception) -> bool:
    # grpc's context.abort() raises a bare ``Exception()`` after recording the status; let it through.
    return type(exc) is Exception and not exc.args


def add_servicer(spec: ContractSpec, servicer: Any, server: grpc.Server) -> None:
    """Register ``servicer`` for ``spec``'s generated gRPC service on ``server``."""
    _, add = generated_servicer(spec)
    add(servicer, server)
