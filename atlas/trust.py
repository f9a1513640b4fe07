"""What the atlas trusts: the deployment token on mutating RPCs, and the hosts endpoints may point at.

robonix's atlas takes any request from anyone who can reach its port. Ours does too when started without
a token (that is robonix's atlas, wire for wire); with one (``rbnx boot`` hands it over as
``$ROBONIX_DEPLOY_TOKEN``) every RPC that changes the registry must carry it in the ``robonix-token``
metadata, while the read side (Query, QueryContract, ListContracts, InspectAtlas) stays open so
dashboards and agents can look without it.

Endpoints: a declared gRPC or MCP endpoint is where consumers will send their goals, so a registry that
accepts ``evil.example.com:443`` redirects them off the machine. Hosts are checked against an allow-list
(loopback by default). No gRPC server plumbing here: the servicer calls :meth:`Trust.refusal`.
"""

from __future__ import annotations

import ipaddress
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from urllib.parse import urlsplit

from robonix_api import auth

#: RPCs that change the registry; the rest of ``robonix.atlas.Atlas`` only reads.
MUTATING_RPCS = frozenset({
    "RegisterPrimitive", "RegisterService", "RegisterSkill", "Unregister", "Heartbeat", "SetLifecycleState",
    "DeclareCapability", "ConnectCapability", "DisconnectCapability",
})
LOOPBACK_NAMES = ("localhost", "localhost.localdomain", "ip6-localhost")
ANY_HOST = "*"
MAX_HOSTS = 256


def parse_allowed_hosts(value: str | Sequence[str] | None) -> tuple[str, ...]:
    """``"a,b"`` or a list -> normalised tuple; ``()`` means the loopback default. ValueError names the
    setting on an empty or malformed entry."""
    if value is None:
        return ()
    items = value.split(",") if isinstance(value, str) else list(value)
    out: list[str] = []
    for raw in items:
        if not isinstance(raw, str):
            raise ValueError(f"allowed_hosts: expected host names, got {type(raw).__name__}")
        host = raw.strip().lower().strip("[]")
        if not host:
            continue
        if len(host) > 253 or any(c.isspace() or c in "/@?#" for c in host):
            raise ValueError(f"allowed_hosts: not a host name or address: {raw[:64]!r}")
        out.append(host)
    if len(out) > MAX_HOSTS:
        raise ValueError(f"allowed_hosts: more than {MAX_HOSTS} entries")
    return tuple(out)


def endpoint_host(endpoint: str) -> str | None:
    """The host of a gRPC (``host:port``, ``grpc://host:port``, ``[::1]:port``, ``dns:///h:p``) or MCP
    (``http://host:port/mcp/``) endpoint, lower case without brackets; "" for a local unix socket;
    None when it has no recognisable host."""
    ep = endpoint.strip()
    if ep.startswith(("unix:", "unix-abstract:")):
        return ""
    if ep.startswith("dns:"):
        ep = ep[4:].lstrip("/")
    if "://" not in ep:
        ep = "//" + ep
    try:
        parts = urlsplit(ep)
        host = parts.hostname
        _ = parts.port  # raises ValueError on a malformed port
    except ValueError:
        return None
    return host.lower() if host else None


def is_loopback(host: str) -> bool:
    if host in LOOPBACK_NAMES:
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


@dataclass(frozen=True)
class Trust:
    """The atlas's trust settings. ``token`` "" = no authentication (robonix's behaviour)."""

    token: str = ""
    allowed_hosts: tuple[str, ...] = ()  # extra hosts beyond loopback; "*" allows any

    def refusal(self, rpc: str, metadata: Iterable[tuple[str, object]] | None) -> tuple[str, str] | None:
        """None when ``rpc`` may run, else (status-code name, message naming what is missing)."""
        if not self.token or rpc not in MUTATING_RPCS:
            return None
        presented = auth.token_from_metadata(metadata)  # type: ignore[arg-type]
        if not presented:
            return ("UNAUTHENTICATED", f"{rpc}: this atlas requires the deployment token in the "
                    f"{auth.METADATA_KEY!r} metadata (`rbnx token` prints it)")
        if not auth.token_matches(self.token, presented):
            return "PERMISSION_DENIED", f"{rpc}: {auth.METADATA_KEY} metadata does not match the deployment token"
        return None

    def holds_token(self, metadata: Iterable[tuple[str, object]] | None) -> bool:
        """True when the caller proved the token, or when there is none to prove (robonix semantics)."""
        if not self.token:
            return True
        return auth.token_matches(self.token, auth.token_from_metadata(metadata))  # type: ignore[arg-type]

    def host_allowed(self, host: str) -> bool:
        if host == "" or is_loopback(host):  # "" = unix socket, local by construction
            return True
        return ANY_HOST in self.allowed_hosts or host in self.allowed_hosts

    def endpoint_problem(self, endpoint: str) -> str | None:
        """None for an acceptable gRPC/MCP endpoint, else the reason (the caller prefixes the field)."""
        host = endpoint_host(endpoint)
        if host is None:
            return f"{endpoint[:128]!r} has no host:port"
        if not self.host_allowed(host):
            extra = ", ".join(self.allowed_hosts)
            return (f"host {host[:64]!r} is not allowed (loopback{', ' + extra if extra else ''}; "
                    "multi-host deployments list theirs in system.atlas.allowed_hosts / ROBONIX_ATLAS_ALLOWED_HOSTS)")
        return None


__all__ = ["ANY_HOST", "MUTATING_RPCS", "Trust", "endpoint_host", "is_loopback", "parse_allowed_hosts"]
