"""The atlas registry: providers, their capabilities, channels and the contract catalogue.

Pure logic, no gRPC: every rule of robonix's atlas (spec §1.5) lives here so it can be unit-tested
with a fake clock, and the servicer in ``atlas.server`` only translates messages. Errors are raised as
``RegistryError(code, message)`` where ``code`` is a gRPC status-code name and the message starts with
the offending field (``"namespace: must not be empty"``).

Deliberate differences from robonix (the issue asks for them):
- minted and collision-rewritten ROS 2 endpoints are valid ROS 2 names (``/rbnx/robonix/x/t1a2b3c4d``,
  ``/odom_t1a2b3c4d``) instead of dotted / double-underscore forms;
- endpoints held by TERMINATED providers do not count as collisions (the owner is gone);
- channels of a provider are dropped when it becomes TERMINATED by any route, and ConnectCapability to
  a TERMINATED provider is refused with FAILED_PRECONDITION.
"""

from __future__ import annotations

import json
import logging
import re
import threading
import time
import uuid
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from atlas.catalogue import Catalogue
from robonix_api.types import (
    Capability,
    CapabilityProvider,
    Channel,
    ContractDescriptor,
    GrpcParams,
    Kind,
    LifecycleState,
    McpParams,
    Ros2Params,
    Transport,
    TransportParams,
    params_to_dict,
)

log = logging.getLogger(__name__)

MINT_ATTEMPTS = 16
EPHEMERAL_PREFIX = "com.robonix.ephemeral."
SHARED_DRIVER = "robonix/lifecycle/driver"  # the Driver under its generic name (every provider of ours)


class RegistryError(Exception):
    """A request the registry refuses; ``code`` is a ``grpc.StatusCode`` name."""

    def __init__(self, code: str, message: str) -> None:
        if len(message) > 1024:  # a status must not echo unbounded input (ids are not length-capped here)
            message = message[:1004] + f"... ({len(message)} chars)"
        super().__init__(f"{code}: {message}")
        self.code = code
        self.message = message


def _invalid(msg: str) -> RegistryError:
    return RegistryError("INVALID_ARGUMENT", msg)


# --------------------------------------------------------------------------- ROS 2 names

_TOKEN = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")


def is_valid_ros2_name(name: str) -> bool:
    """True for a valid ROS 2 topic/service name: absolute (``/a/b``), relative (``a/b``) or private
    (``~/a``); tokens of ``[A-Za-z0-9_]`` that do not start with a digit, contain no ``__`` and do not
    end with ``_``; no empty token, no trailing ``/``."""
    if not name or not isinstance(name, str):
        return False
    rest = name
    if rest == "~":
        return True
    if rest.startswith("~/"):
        rest = rest[2:]
    elif rest.startswith("/"):
        rest = rest[1:]
    if not rest:
        return False  # "/" or "~/" alone names nothing
    for token in rest.split("/"):
        if not _TOKEN.match(token) or "__" in token or token.endswith("_"):
            return False
    return True


def _ros2_token(text: str) -> str:
    """Squeeze arbitrary text (a contract id segment) into one valid ROS 2 name token."""
    tok = re.sub(r"[^A-Za-z0-9_]", "_", text)
    tok = re.sub(r"_+", "_", tok).strip("_")
    if not tok:
        return "x"
    return f"c{tok}" if tok[0].isdigit() else tok


def _uuid_token() -> str:
    """8 hex chars of a uuid4 behind a letter, so the token never starts with a digit."""
    return "t" + uuid.uuid4().hex[:8]


def mint_ros2_endpoint(contract_id: str) -> str:
    """``robonix/primitive/chassis/odom`` -> ``/rbnx/robonix/primitive/chassis/odom/t1a2b3c4d``."""
    parts = [_ros2_token(seg) for seg in contract_id.split("/") if seg]
    return "/" + "/".join(["rbnx", *parts, _uuid_token()])


def rewrite_ros2_endpoint(proposed: str) -> str:
    """A colliding ROS 2 name made unique and still valid: ``/odom`` -> ``/odom_t1a2b3c4d``."""
    return f"{proposed.rstrip('_/')}_{_uuid_token()}"


# --------------------------------------------------------------------------- records


@dataclass
class _Cap:
    contract_id: str
    transport: Transport
    endpoint: str
    params: TransportParams
    description: str
    namespace_mismatch: bool


@dataclass
class _Provider:
    id: str
    kind: Kind
    namespace: str
    capability_md_path: str
    capability_md: str
    registration_id: str
    last_heartbeat_ms: int
    hb_mono: float
    pushed_state: LifecycleState | None = None
    state_detail: str = ""
    caps: dict[tuple[str, Transport], _Cap] = field(default_factory=dict)

    @property
    def state(self) -> LifecycleState:
        """robonix rule: never pushed -> INACTIVE once a non-driver capability exists, else REGISTERED."""
        if self.pushed_state is not None:
            return self.pushed_state
        if any(not cid.endswith("/driver") for cid, _ in self.caps):
            return LifecycleState.INACTIVE
        return LifecycleState.REGISTERED


@dataclass
class _Channel:
    channel_id: str
    consumer_id: str
    provider_id: str
    contract_id: str
    transport: Transport
    endpoint: str
    params: TransportParams
    opened_ms: int


_LEGAL_EDGES = {
    (LifecycleState.REGISTERED, LifecycleState.INACTIVE),
    (LifecycleState.INACTIVE, LifecycleState.ACTIVE),
    (LifecycleState.ACTIVE, LifecycleState.INACTIVE),
    (LifecycleState.ERROR, LifecycleState.INACTIVE),
}


class Registry:
    """Thread-safe registry (one lock). ``clock`` is monotonic seconds (eviction), ``wall_clock`` epoch
    seconds (the ``last_heartbeat_ms`` reported on the wire); both injectable for tests."""

    def __init__(
        self,
        catalogue: Catalogue | None = None,
        *,
        heartbeat_timeout_ms: int = 90000,
        gc_after_terminated_ms: int = 600000,
        clock: Callable[[], float] = time.monotonic,
        wall_clock: Callable[[], float] = time.time,
    ) -> None:
        self.catalogue = catalogue if catalogue is not None else Catalogue()
        self.heartbeat_timeout_ms = int(heartbeat_timeout_ms)
        self.gc_after_terminated_ms = int(gc_after_terminated_ms)
        self._clock = clock
        self._wall = wall_clock
        self._lock = threading.Lock()
        self._providers: dict[str, _Provider] = {}
        self._channels: dict[str, _Channel] = {}
        self._by_contract: dict[str, set[str]] = {}
        self._endpoints: dict[tuple[Transport, str], set[str]] = {}

    # ----------------------------------------------------------------- helpers (lock held)

    def _now_ms(self) -> int:
        return int(self._wall() * 1000)

    def _get(self, pid: str, field_name: str = "id") -> _Provider:
        if not pid:
            raise _invalid(f"{field_name}: must not be empty")
        p = self._providers.get(pid)
        if p is None:
            raise RegistryError("NOT_FOUND", f"{field_name}: no provider {pid!r} is registered")
        return p

    def _clear_caps(self, p: _Provider) -> None:
        for (cid, transport), cap in p.caps.items():
            owners = self._by_contract.get(cid)
            if owners is not None:
                owners.discard(p.id)
                if not owners:
                    del self._by_contract[cid]
            key = (transport, cap.endpoint)
            eps = self._endpoints.get(key)
            if eps is not None:
                eps.discard(p.id)
                if not eps:
                    del self._endpoints[key]
        p.caps.clear()

    def _drop_channels(self, pid: str) -> int:
        """Drop channels where pid is the provider or the consumer (both ends are stale then)."""
        dead = [c for c, ch in self._channels.items() if pid in (ch.provider_id, ch.consumer_id)]
        for c in dead:
            del self._channels[c]
        return len(dead)

    def _remove(self, p: _Provider) -> None:
        self._clear_caps(p)
        self._drop_channels(p.id)
        del self._providers[p.id]

    def _namespace_mismatch(self, namespace: str, contract_id: str) -> bool:
        desc = self.catalogue.get(contract_id)
        if desc is not None and desc.cross_namespace:
            return False
        ns = namespace.strip("/")
        return not (contract_id == ns or contract_id.startswith(ns + "/"))

    def _foreign_owners(self, transport: Transport, endpoint: str, me: str) -> list[str]:
        owners = self._endpoints.get((transport, endpoint), ())
        return sorted(o for o in owners if o != me and self._providers[o].state != LifecycleState.TERMINATED)

    # ----------------------------------------------------------------- providers

    def register(
        self, kind: Kind, id: str, namespace: str, capability_md_path: str = "", capability_md: str = ""
    ) -> str:
        """Register or take over ``id`` (same kind); returns the id (assigned when empty)."""
        kind = Kind(kind)
        if kind == Kind.UNSPECIFIED:
            raise _invalid("kind: must be primitive, service or skill")
        if not namespace:
            raise _invalid("namespace: must not be empty")
        pid = id or f"{EPHEMERAL_PREFIX}{uuid.uuid4()}"
        with self._lock:
            old = self._providers.get(pid)
            if old is not None:
                if old.kind != kind:
                    raise RegistryError(
                        "ALREADY_EXISTS",
                        f"id: {pid!r} is already registered as a {old.kind.label}, not a {kind.label}",
                    )
                log.info("register %s: takeover of registration %s", pid, old.registration_id)
                self._remove(old)
            self._providers[pid] = _Provider(
                id=pid,
                kind=kind,
                namespace=namespace,
                capability_md_path=capability_md_path,
                capability_md=capability_md,
                registration_id=str(uuid.uuid4()),
                last_heartbeat_ms=self._now_ms(),
                hb_mono=self._clock(),
            )
        log.info("registered %s %s (namespace %s)", kind.label, pid, namespace)
        return pid

    def unregister(self, id: str) -> bool:
        """Idempotent; drops the provider's channels too."""
        with self._lock:
            p = self._providers.get(id)
            if p is None:
                return False
            self._remove(p)
        log.info("unregistered %s", id)
        return True

    def heartbeat(self, id: str) -> None:
        """Only refreshes ``last_heartbeat``; a TERMINATED provider stays TERMINATED (robonix rule)."""
        with self._lock:
            p = self._get(id)
            p.last_heartbeat_ms = self._now_ms()
            p.hb_mono = self._clock()

    def set_state(self, id: str, state: LifecycleState, detail: str = "") -> LifecycleState:
        """Store the pushed state (an unusual edge is logged, not refused); returns the previous one."""
        try:
            state = LifecycleState(state)
        except ValueError:
            raise _invalid(f"state: unknown value {state}") from None
        if state == LifecycleState.UNSPECIFIED:
            raise _invalid("state: must not be STATE_UNSPECIFIED")
        with self._lock:
            p = self._get(id)
            prev = p.state
            if prev != state and state not in (LifecycleState.ERROR, LifecycleState.TERMINATED):
                if (prev, state) not in _LEGAL_EDGES:
                    log.warning("%s: unusual lifecycle edge %s -> %s (stored)", id, prev.name, state.name)
            p.pushed_state = state
            p.state_detail = detail
            if state == LifecycleState.TERMINATED:
                self._drop_channels(id)
        return prev

    # ----------------------------------------------------------------- capabilities

    def declare(
        self,
        provider_id: str,
        contract_id: str,
        transport: Transport | int,
        endpoint: str,
        params: TransportParams | None,
        description: str = "",
    ) -> str:
        """Declare one (contract, transport) of a provider; returns the endpoint actually stored."""
        if not provider_id:
            raise _invalid("provider_id: must not be empty")
        if not contract_id:
            raise _invalid("contract_id: must not be empty")
        try:
            transport = Transport(transport)
        except ValueError:
            raise _invalid(f"transport: unknown value {transport}") from None
        if transport == Transport.UNSPECIFIED:
            raise _invalid("transport: must be TRANSPORT_GRPC, TRANSPORT_ROS2 or TRANSPORT_MCP")
        if params is None:
            raise _invalid(f"params: must be set (params.{transport.label} for transport {transport.name})")
        if params.transport != transport:
            raise _invalid(
                f"params: params.{params.transport.label} does not match transport {transport.name}"
            )
        if isinstance(params, McpParams) and params.input_schema_json:
            try:
                schema = json.loads(params.input_schema_json)
            except ValueError as exc:
                raise _invalid(f"params.mcp.input_schema_json: not valid JSON ({exc})") from None
            if not isinstance(schema, dict):
                raise _invalid("params.mcp.input_schema_json: must be a JSON object")
        if not endpoint and transport != Transport.ROS2:
            raise _invalid(f"endpoint: must not be empty for transport {transport.name}")

        with self._lock:
            p = self._get(provider_id, "provider_id")
            key = (contract_id, transport)
            if key in p.caps:
                raise RegistryError(
                    "ALREADY_EXISTS",
                    f"contract_id: {contract_id!r} over {transport.name} is already declared by {p.id!r}",
                )
            if contract_id.endswith("/driver") and contract_id != SHARED_DRIVER:
                # robonix rule: one driver per provider. The shared robonix/lifecycle/driver is the same
                # Driver under its generic name, so it may stand next to the provider's <namespace>/driver.
                other = next((c for c, _ in p.caps
                              if c.endswith("/driver") and c not in (contract_id, SHARED_DRIVER)), None)
                if other is not None:
                    raise RegistryError(
                        "FAILED_PRECONDITION",
                        f"contract_id: {p.id!r} already declares driver {other!r}; "
                        f"a provider has one driver, cannot add {contract_id!r}",
                    )
            ep = self._resolve_endpoint(p.id, contract_id, transport, endpoint)
            mismatch = self._namespace_mismatch(p.namespace, contract_id)
            if mismatch:
                log.info("%s: contract %s is outside namespace %s", p.id, contract_id, p.namespace)
            p.caps[key] = _Cap(contract_id, transport, ep, params, description, mismatch)
            self._by_contract.setdefault(contract_id, set()).add(p.id)
            self._endpoints.setdefault((transport, ep), set()).add(p.id)
        return ep

    def _resolve_endpoint(self, pid: str, contract_id: str, transport: Transport, endpoint: str) -> str:
        if not endpoint:  # only ROS 2 gets here
            for _ in range(MINT_ATTEMPTS):
                ep = mint_ros2_endpoint(contract_id)
                if (transport, ep) not in self._endpoints:
                    return ep
            raise RegistryError("INTERNAL", "endpoint: could not mint a unique ROS 2 name")
        owners = self._foreign_owners(transport, endpoint, pid)
        if not owners:
            return endpoint
        if transport != Transport.ROS2:
            raise RegistryError(
                "ALREADY_EXISTS",
                f"endpoint: {endpoint!r} over {transport.name} is already declared by {owners[0]!r}",
            )
        for _ in range(MINT_ATTEMPTS):
            ep = rewrite_ros2_endpoint(endpoint)
            if (transport, ep) not in self._endpoints:
                log.info("%s: ROS 2 endpoint %s taken by %s, rewritten to %s", pid, endpoint, owners[0], ep)
                return ep
        raise RegistryError("INTERNAL", f"endpoint: could not rewrite colliding ROS 2 name {endpoint!r}")

    # ----------------------------------------------------------------- queries

    def _view(self, p: _Provider, caps: list[_Cap]) -> CapabilityProvider:
        return CapabilityProvider(
            id=p.id,
            kind=p.kind,
            namespace=p.namespace,
            capability_md_path=p.capability_md_path,
            last_heartbeat_ms=p.last_heartbeat_ms,
            state=p.state,
            state_detail=p.state_detail,
            capabilities=[
                Capability(
                    p.id, p.kind, c.contract_id, c.transport, c.params, c.description, c.namespace_mismatch
                )
                for c in caps
            ],
            capability_md=p.capability_md,
            registration_id=p.registration_id,
        )

    def query(
        self,
        kind: Kind | int = Kind.UNSPECIFIED,
        id: str = "",
        contract_id: str = "",
        transport: Transport | int = Transport.UNSPECIFIED,
        namespace_prefix: str = "",
    ) -> list[CapabilityProvider]:
        """robonix Query: empty/UNSPECIFIED (or unknown enum) = no filter; with contract_id, providers
        lacking it are dropped; capabilities are filtered by contract and transport, but a provider is
        kept when only the transport filter empties its list. Sorted by provider id."""
        kind = Kind(kind) if kind in Kind._value2member_map_ else Kind.UNSPECIFIED
        transport = (
            Transport(transport) if transport in Transport._value2member_map_ else Transport.UNSPECIFIED
        )
        with self._lock:
            if id:
                ids: Any = [id] if id in self._providers else []
            elif contract_id:
                ids = self._by_contract.get(contract_id, ())
            else:
                ids = self._providers.keys()
            out = []
            for pid in sorted(ids):
                p = self._providers[pid]
                if kind and p.kind != kind:
                    continue
                if namespace_prefix and not p.namespace.startswith(namespace_prefix):
                    continue
                if contract_id and pid not in self._by_contract.get(contract_id, ()):
                    continue
                caps = [
                    c
                    for c in p.caps.values()
                    if (not contract_id or c.contract_id == contract_id)
                    and (not transport or c.transport == transport)
                ]
                out.append(self._view(p, caps))
            return out

    def connect(
        self, consumer_id: str, provider_id: str, contract_id: str, transport: Transport | int
    ) -> Channel:
        """Open a channel to a declared (contract, transport) of a live provider."""
        for name, value in (
            ("consumer_id", consumer_id),
            ("provider_id", provider_id),
            ("contract_id", contract_id),
        ):
            if not value:
                raise _invalid(f"{name}: must not be empty")
        try:
            transport = Transport(transport)
        except ValueError:
            raise _invalid(f"transport: unknown value {transport}") from None
        if transport == Transport.UNSPECIFIED:
            raise _invalid("transport: must not be TRANSPORT_UNSPECIFIED")
        with self._lock:
            p = self._get(provider_id, "provider_id")
            cap = p.caps.get((contract_id, transport))
            if cap is None:
                raise RegistryError(
                    "NOT_FOUND",
                    f"contract_id: provider {provider_id!r} has no capability {contract_id!r} "
                    f"over {transport.name}",
                )
            if p.state == LifecycleState.TERMINATED:
                # robonix's atlas opens the channel all the same (its record keeps the endpoints until GC);
                # consumers that want live providers filter on state, as find_capability does.
                log.info("connect %s -> %s: provider is TERMINATED (%s)", consumer_id, provider_id,
                         p.state_detail or "no detail")
            ch = _Channel(
                channel_id="ch-" + uuid.uuid4().hex,
                consumer_id=consumer_id,
                provider_id=provider_id,
                contract_id=contract_id,
                transport=transport,
                endpoint=cap.endpoint,
                params=cap.params,
                opened_ms=self._now_ms(),
            )
            self._channels[ch.channel_id] = ch
        return Channel(ch.channel_id, ch.endpoint, ch.params, provider_id, contract_id, transport)

    def disconnect(self, channel_id: str) -> bool:
        with self._lock:
            return self._channels.pop(channel_id, None) is not None

    def channel_count(self, provider_id: str | None = None) -> int:
        with self._lock:
            if provider_id is None:
                return len(self._channels)
            return sum(1 for ch in self._channels.values() if provider_id in (ch.provider_id, ch.consumer_id))

    # ----------------------------------------------------------------- contracts

    def query_contract(self, contract_id: str) -> ContractDescriptor | None:
        if not contract_id:
            raise _invalid("contract_id: must not be empty")
        return self.catalogue.get(contract_id)

    def list_contracts(self, prefix: str = "") -> list[ContractDescriptor]:
        return self.catalogue.list(prefix)

    # ----------------------------------------------------------------- eviction & inspection

    def sweep(self) -> tuple[list[str], list[str]]:
        """Mark lapsed providers TERMINATED (dropping their channels) and remove TERMINATED records past
        ``timeout + gc``. Returns (evicted ids, removed ids). A timeout of 0 disables both."""
        timeout = self.heartbeat_timeout_ms
        if timeout <= 0:
            return [], []
        now = self._clock()
        evicted: list[str] = []
        removed: list[str] = []
        with self._lock:
            for p in list(self._providers.values()):
                idle_ms = (now - p.hb_mono) * 1000.0
                if p.state == LifecycleState.TERMINATED:
                    if idle_ms > timeout + self.gc_after_terminated_ms:
                        self._remove(p)
                        removed.append(p.id)
                elif idle_ms > timeout:
                    p.pushed_state = LifecycleState.TERMINATED
                    p.state_detail = f"heartbeat lapsed > {timeout}ms"
                    self._drop_channels(p.id)
                    evicted.append(p.id)
        for pid in evicted:
            log.warning("%s: heartbeat lapsed > %dms, marked TERMINATED", pid, timeout)
        for pid in removed:
            log.info("%s: TERMINATED record removed", pid)
        return evicted, removed

    def snapshot(self) -> dict[str, Any]:
        """Everything, JSON-ready (InspectAtlas)."""
        with self._lock:
            providers = []
            caps = []
            for pid in sorted(self._providers):
                p = self._providers[pid]
                pcaps = [
                    {
                        "provider_id": p.id,
                        "contract_id": c.contract_id,
                        "transport": c.transport.label,
                        "endpoint": c.endpoint,
                        "params": params_to_dict(c.params),
                        "description": c.description,
                        "namespace_mismatch": c.namespace_mismatch,
                    }
                    for c in p.caps.values()
                ]
                caps.extend(pcaps)
                providers.append(
                    {
                        "id": p.id,
                        "kind": p.kind.label,
                        "namespace": p.namespace,
                        "state": p.state.label,
                        "state_detail": p.state_detail,
                        "last_heartbeat_ms": p.last_heartbeat_ms,
                        "registration_id": p.registration_id,
                        "capability_md_path": p.capability_md_path,
                        "capabilities": [
                            {k: c[k] for k in ("contract_id", "transport", "endpoint")} for c in pcaps
                        ],
                    }
                )
            channels = [
                {
                    "channel_id": ch.channel_id,
                    "consumer_id": ch.consumer_id,
                    "provider_id": ch.provider_id,
                    "contract_id": ch.contract_id,
                    "transport": ch.transport.label,
                    "endpoint": ch.endpoint,
                    "opened_ms": ch.opened_ms,
                }
                for ch in self._channels.values()
            ]
        return {
            "providers": providers,
            "capabilities": caps,
            "channels": channels,
            "contracts": len(self.catalogue),
            "heartbeat_timeout_ms": self.heartbeat_timeout_ms,
            "now_ms": self._now_ms(),
        }


__all__ = [
    "GrpcParams",
    "McpParams",
    "Registry",
    "RegistryError",
    "Ros2Params",
    "is_valid_ros2_name",
    "mint_ros2_endpoint",
    "rewrite_ros2_endpoint",
]
