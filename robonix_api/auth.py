"""The deployment token: who may change the registry, drive a lifecycle or call a state-changing contract.

``rbnx boot`` makes one random token per deployment and hands it to the atlas and every child as
``$ROBONIX_DEPLOY_TOKEN``. Everything that changes state then wants it: the atlas's mutating RPCs, every
provider's Driver and its state-changing contracts (gRPC and MCP), the deployment's MCP gateway. Our
clients attach it from the environment by themselves, so a package never handles it.

On the wire it travels as gRPC metadata ``robonix-token: <token>`` or as the HTTP header
``Authorization: Bearer <token>`` (MCP; ``robonix-token`` is accepted there too). With no token in the
environment nothing is checked and nothing is sent: an atlas started that way is robonix's atlas.

No gRPC server import here beyond ``grpc`` itself, and no MCP import at all: providers load this at start.
"""

from __future__ import annotations

import hmac
import os
from collections.abc import Callable, Iterable, Mapping
from typing import Any

import grpc

TOKEN_ENV = "ROBONIX_DEPLOY_TOKEN"
METADATA_KEY = "robonix-token"  # gRPC metadata keys are lower case
MAX_TOKEN_LEN = 256

#: Contracts that only read state; everything else a provider serves needs the token when one is set.
READ_ONLY_CONTRACTS = frozenset({
    "robonix/service/navigation/navigate/status",
    "robonix/service/navigation/get_speed_limit",
    "robonix/service/map/list_maps",
    "robonix/service/map/get_mode",
    "robonix/service/map/get_pose",
    "robonix/service/map/map_card",
    "robonix/primitive/sim/scene_info",
    "robonix/primitive/sim/ground_truth",
    "robonix/primitive/sim/collisions",
})


def current_token() -> str:
    """This process's deployment token ("" when none is set: nothing is checked or sent)."""
    return os.environ.get(TOKEN_ENV, "").strip()


def is_read_only(contract_id: str) -> bool:
    """Whether ``contract_id`` only reads state, so it is served without the deployment token."""
    return contract_id in READ_ONLY_CONTRACTS


def read_only_tool_names() -> frozenset[str]:
    """MCP tool names (last contract segment) of the read-only contracts (``status``, ``get_pose``, …)."""
    return frozenset(cid.rsplit("/", 1)[-1] for cid in READ_ONLY_CONTRACTS)


def token_matches(expected: str, presented: str | bytes | None) -> bool:
    """Constant-time comparison; an absent or over-long presented token never matches."""
    if not expected or presented is None:
        return False
    if isinstance(presented, str):
        presented = presented.encode("utf-8", "replace")
    if len(presented) > MAX_TOKEN_LEN:
        return False
    return hmac.compare_digest(expected.encode(), presented)


def token_from_metadata(metadata: Iterable[tuple[str, Any]] | None) -> str | None:
    """The ``robonix-token`` value of gRPC invocation metadata, or None."""
    for key, value in metadata or ():
        if key == METADATA_KEY:
            return value.decode("utf-8", "replace") if isinstance(value, bytes) else str(value)
    return None


def token_from_headers(headers: Mapping[str, str] | None) -> str | None:
    """The token of HTTP headers: ``Authorization: Bearer <token>`` or ``robonix-token: <token>``."""
    if not headers:
        return None
    direct = headers.get(METADATA_KEY)
    if direct:
        return direct.strip()
    auth = headers.get("authorization") or headers.get("Authorization") or ""
    scheme, _, value = auth.strip().partition(" ")
    if scheme.lower() == "bearer" and value.strip():
        return value.strip()
    return None


def refusal(presented: str | None, what: str) -> tuple[grpc.StatusCode, str] | None:
    """None when ``presented`` is this process's token (or no token is set), else (status, message)."""
    expected = current_token()
    if not expected:
        return None
    if not presented:
        return (grpc.StatusCode.UNAUTHENTICATED,
                f"{what}: deployment token required ({METADATA_KEY} metadata or Authorization: Bearer; "
                "`rbnx token` prints it)")
    if not token_matches(expected, presented):
        return grpc.StatusCode.PERMISSION_DENIED, f"{what}: wrong deployment token"
    return None


def metadata(extra: Iterable[tuple[str, str]] | None = None) -> list[tuple[str, str]] | None:
    """Call metadata carrying this process's token (plus ``extra``); None when there is nothing to send."""
    out = list(extra or ())
    token = current_token()
    if token and not any(k == METADATA_KEY for k, _ in out):
        out.append((METADATA_KEY, token))
    return out or None


def http_headers() -> dict[str, str]:
    """HTTP headers carrying this process's token (for MCP clients); empty without one."""
    token = current_token()
    return {"Authorization": f"Bearer {token}"} if token else {}


# --------------------------------------------------------------------------- gRPC client side


class _ClientCallDetails(grpc.ClientCallDetails):
    def __init__(self, base: grpc.ClientCallDetails, metadata: list[tuple[str, str]]) -> None:
        self.method = base.method
        self.timeout = base.timeout
        self.metadata = metadata
        self.credentials = base.credentials
        self.wait_for_ready = getattr(base, "wait_for_ready", None)
        self.compression = getattr(base, "compression", None)


class TokenClientInterceptor(grpc.UnaryUnaryClientInterceptor, grpc.UnaryStreamClientInterceptor):
    """Adds ``robonix-token`` to every call when the environment holds a token (read per call, so a
    token set after the channel was made is still sent)."""

    def __init__(self, token: Callable[[], str] = current_token) -> None:
        self._token = token

    def _details(self, details: grpc.ClientCallDetails) -> grpc.ClientCallDetails:
        token = self._token()
        md = list(details.metadata or ())
        if not token or any(k == METADATA_KEY for k, _ in md):
            return details
        md.append((METADATA_KEY, token))
        return _ClientCallDetails(details, md)

    def intercept_unary_unary(self, continuation: Any, client_call_details: Any, request: Any) -> Any:
        """Add the token to a unary call's metadata."""
        return continuation(self._details(client_call_details), request)

    def intercept_unary_stream(self, continuation: Any, client_call_details: Any, request: Any) -> Any:
        """Add the token to a server-streaming call's metadata."""
        return continuation(self._details(client_call_details), request)


def channel(target: str, options: list[tuple[str, Any]] | None = None) -> grpc.Channel:
    """``grpc.insecure_channel`` that sends the deployment token on every call (loopback plaintext)."""
    base = grpc.insecure_channel(target, options=options or [("grpc.enable_http_proxy", 0)])
    return grpc.intercept_channel(base, TokenClientInterceptor())


# --------------------------------------------------------------------------- gRPC server side


class TokenServerInterceptor(grpc.ServerInterceptor):
    """Refuses calls to methods that ``protected(method_path)`` names unless they carry the token.

    Checked against the token in the environment at call time; with none set every call passes.
    """

    def __init__(self, protected: Callable[[str], bool]) -> None:
        self._protected = protected

    def intercept_service(self, continuation: Any, handler_call_details: Any) -> Any:
        """Refuse a protected method called without the right deployment token (status and message from
        :func:`refusal`); pass every other call through."""
        method = handler_call_details.method or ""
        if not current_token() or not self._protected(method):
            return continuation(handler_call_details)
        bad = refusal(token_from_metadata(handler_call_details.invocation_metadata), method.rsplit("/", 1)[-1])
        if bad is None:
            return continuation(handler_call_details)
        code, message = bad
        handler = continuation(handler_call_details)
        if handler is None:
            return None

        def deny(_request: Any, context: grpc.ServicerContext) -> Any:
            context.abort(code, message)

        if handler.unary_unary is not None:
            return grpc.unary_unary_rpc_method_handler(deny, handler.request_deserializer,
                                                       handler.response_serializer)
        if handler.unary_stream is not None:
            return grpc.unary_stream_rpc_method_handler(deny, handler.request_deserializer,
                                                        handler.response_serializer)
        return handler  # streaming-request methods: none of ours


__all__ = [
    "METADATA_KEY",
    "READ_ONLY_CONTRACTS",
    "TOKEN_ENV",
    "TokenClientInterceptor",
    "TokenServerInterceptor",
    "channel",
    "current_token",
    "http_headers",
    "is_read_only",
    "metadata",
    "read_only_tool_names",
    "refusal",
    "token_from_headers",
    "token_from_metadata",
    "token_matches",
]


# --------------------------------------------------------------------------- MCP client side


def mcp_client(url: str, **kwargs: Any) -> Any:
    """An official MCP ``Client`` for ``url`` that sends this process's token as ``Authorization:
    Bearer`` (a plain ``Client(url)`` without one). Use as ``async with mcp_client(url) as c:``."""
    from contextlib import asynccontextmanager

    from mcp import Client

    headers = http_headers()
    if not headers:
        return Client(url, **kwargs)

    @asynccontextmanager
    async def _with_headers() -> Any:
        from mcp.client.streamable_http import streamable_http_client
        from mcp.shared._httpx_utils import create_mcp_http_client

        async with create_mcp_http_client(headers=headers) as http, \
                Client(streamable_http_client(url, http_client=http), **kwargs) as client:
            yield client

    return _with_headers()
