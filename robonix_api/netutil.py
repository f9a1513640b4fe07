"""Where a provider binds and which host it advertises in the endpoints it declares to the atlas.

We bind loopback by default (robonix binds 0.0.0.0) so nothing is exposed unless asked for; the
advertised host must be reachable by consumers, hence the robonix fallback chain.
"""

from __future__ import annotations

import ipaddress
import os
import socket

DEFAULT_BIND_HOST = "127.0.0.1"
WILDCARD_V4 = "0.0.0.0"  # "any interface": never our default, but a user may bind it on a robot
_WILDCARDS = {"", WILDCARD_V4, "::", "[::]"}


def bind_host() -> str:
    """``ROBONIX_PROVIDER_BIND_HOST`` (an IPv4 literal), default ``127.0.0.1``."""
    host = os.environ.get("ROBONIX_PROVIDER_BIND_HOST", "").strip() or DEFAULT_BIND_HOST
    try:
        ipaddress.IPv4Address(host)
    except ValueError:
        raise ValueError(f"ROBONIX_PROVIDER_BIND_HOST must be an IPv4 literal, got {host!r}") from None
    return host


def is_wildcard(host: str) -> bool:
    """Whether ``host`` means every interface (0.0.0.0, ::, empty), which is no address to dial."""
    return host.strip() in _WILDCARDS


def route_source_toward(address: str) -> str | None:
    """Local IPv4 address the kernel would use to reach ``address`` ("host:port"); None if unknown.

    A UDP ``connect`` sends nothing; it only asks the routing table.
    """
    host, _, port = address.rpartition(":")
    host = host.strip("[]") or address
    try:
        infos = socket.getaddrinfo(host, int(port or 50051), socket.AF_INET, socket.SOCK_DGRAM)
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
            s.connect(infos[0][4])
            src = s.getsockname()[0]
    except (OSError, ValueError, IndexError):
        return None
    return None if is_wildcard(src) else src


def advertise_host(bind: str, atlas_address: str) -> str:
    """``ROBONIX_ADVERTISE_HOST``, else the bind host if not a wildcard, else the route source toward the
    atlas, else ``127.0.0.1``."""
    env = os.environ.get("ROBONIX_ADVERTISE_HOST", "").strip()
    if env:
        return env
    if not is_wildcard(bind):
        return bind
    return route_source_toward(atlas_address) or "127.0.0.1"


def host_port(host: str, port: int) -> str:
    """``host:port`` with IPv6 literals bracketed (gRPC endpoints carry no scheme)."""
    return f"[{host}]:{port}" if ":" in host else f"{host}:{port}"


def bind_listener(host: str, *, listen: bool = True) -> socket.socket:
    """A TCP socket bound to port 0 of ``host``; listening already when ``listen`` (clients that connect
    then wait in the backlog until a server takes the socket over)."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    sock.bind((host, 0))
    if listen:
        sock.listen(128)
    return sock
