"""robonix-api 0.1.0rc1 names on a provider that this SDK's own names did not cover.

Mixed into :class:`robonix_api.provider._Provider`: ``provides_grpc``/``provides_mcp`` (robonix-api's
spelling of ``@svc.grpc``/``@svc.mcp``), ``connect_capability`` (channels closed on teardown),
``declare_ros2_service``, ``use_mcp_app``, ``mcp_endpoint``, ``bootstrap`` and ``resolve_host_ip``.
Kept apart from the provider's core so the lifecycle/atlas plumbing stays readable.
"""

from __future__ import annotations

import logging
import socket
from collections.abc import Callable
from typing import Any, TypeVar

from robonix_api.types import Capability, CapabilityProvider, Channel, Ros2Params, Transport

log = logging.getLogger("robonix_api.provider")
F = TypeVar("F", bound=Callable[..., Any])


def check_namespace(namespace: str) -> str:
    """robonix-api's rule: surrounding slashes dropped, an empty namespace is a ``ValueError``."""
    ns = str(namespace).strip().strip("/")
    if not ns:
        raise ValueError("namespace must be non-empty")
    return ns


class RobonixProviderMixin:
    """Needs from the host class: ``id``, ``atlas``, ``grpc``, ``mcp``, ``declare_capability``,
    ``start``, ``mcp_url`` and ``_mcp_handlers``."""

    def _init_compat(self) -> None:
        self._channels: list[Channel] = []
        self._mcp_app: Any = None
        self._mcp_app_server: Any = None

    # ------------------------------------------------------------------ decorators (robonix-api spelling)

    def provides_grpc(self, contract_id: str, *, description: str = "") -> Callable[[F], F]:
        """robonix-api's name for ``@svc.grpc``: serve ``fn(req)`` / ``fn(req, ctx)`` as the contract's
        gRPC method; ``description`` (else the docstring) is declared with it."""
        return self.grpc(contract_id, description=description)  # type: ignore[attr-defined]

    def provides_mcp(self, contract_id: str, *, description: str = "") -> Callable[[F], F]:
        """robonix-api's name for ``@svc.mcp``: an MCP tool named after the contract's last segment."""
        return self.mcp(contract_id, description=description)  # type: ignore[attr-defined]

    def use_mcp_app(self, app: Any) -> None:
        """Serve a ready-made MCP server app (anything with ``streamable_http_app()``, e.g. the official
        ``mcp`` package's ``MCPServer``) at :attr:`mcp_endpoint`; tools registered on it with
        ``mcp_contract`` are declared to the atlas. Conflicts with ``@provides_mcp`` (RuntimeError)."""
        if self._mcp_handlers:  # type: ignore[attr-defined]
            raise RuntimeError("MCP app already set; use_mcp_app conflicts with @provides_mcp")
        if self._mcp_app is not None and self._mcp_app is not app:
            raise RuntimeError("MCP app already set; use_mcp_app called twice with different apps")
        self._mcp_app = app

    @property
    def mcp_endpoint(self) -> str:
        """``http://host:port/mcp/`` of this provider's MCP server (empty before it serves)."""
        return self.mcp_url  # type: ignore[attr-defined,no-any-return]

    def bootstrap(self) -> None:
        """Register, serve and declare without blocking (idempotent); ``run()`` also waits for the end."""
        if getattr(self, "_grpc_server", None) is not None:
            return
        self.start()  # type: ignore[attr-defined]

    # ------------------------------------------------------------------ declaring / consuming

    def declare_ros2_service(self, contract_id: str, service: str, *, description: str = "") -> str:
        """Declare a ROS 2 service name for an rpc contract (robonix-api; empty QoS profile)."""
        return self.declare_capability(contract_id, service, Transport.ROS2,  # type: ignore[attr-defined]
                                       Ros2Params(qos_profile=""), description)

    def connect_capability(self, provider: CapabilityProvider | Capability | str, contract_id: str,
                           transport: Transport | str | int) -> Channel:
        """Open a channel from this provider to ``provider``'s capability (a record from ``ATLAS.query*``,
        a ``Capability`` from ``find_capability``, or a provider id). Closed on teardown if still open."""
        if isinstance(provider, CapabilityProvider):
            provider_id = provider.id
        elif isinstance(provider, Capability):
            provider_id = provider.provider_id
        else:
            provider_id = str(provider)
        ch = self.atlas.connect_capability(consumer_id=self.id, provider_id=provider_id,  # type: ignore[attr-defined]
                                           contract_id=contract_id, transport=transport)
        self._channels.append(ch)
        return ch

    def _close_channels(self) -> None:
        for ch in self._channels:
            try:
                ch.close()
            except Exception as exc:  # best effort: the atlas may be gone already
                log.debug("closing channel %s: %s", ch.channel_id, exc)
        self._channels.clear()

    def _start_mcp_app(self, bind: str) -> int:
        """Serve the ``use_mcp_app`` app on ``bind`` (port chosen by the OS); returns the port."""
        from robonix_api.mcp_server import MCP_PATH, AsgiServer

        app = self._mcp_app.streamable_http_app(streamable_http_path=MCP_PATH, host=bind)
        self._mcp_app_server = AsgiServer(app, host=bind)
        return self._mcp_app_server.start()

    # ------------------------------------------------------------------ helpers

    def resolve_host_ip(self, target_ip: str) -> str | None:
        """The local IPv4 address the kernel would use to reach ``target_ip`` (None if no route)."""
        try:
            with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
                s.connect((target_ip, 9))  # UDP connect sends nothing; it only consults the routing table
                src = s.getsockname()[0]
        except (OSError, ValueError):
            return None
        return None if src in ("0.0.0.0", "") else src


__all__ = ["RobonixProviderMixin", "check_namespace"]
