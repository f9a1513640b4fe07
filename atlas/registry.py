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
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from atlas.catalogue import Catalogue
from robonix_api import types as rt

log = logging.getLogger(__name__)

MINT_ATTEMPTS = 16
CHANNEL_LEASE_MS = 300_000  # a channel not renewed (consumer heartbeat, reconnect) for this long expires
MAX_CHANNELS_PER_CONSUMER = 64
MAX_CHANNELS = 2048
MAX_SNAPSHOT_CHANNELS = 500  # InspectAtlas lists the newest ones; the reply stays far below gRPC's 4 MB
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
    return all(_TOKEN.match(token) and "__" not in token and not token.endswith("_") for token in rest.split("/"))


def _check_transport_params(transport: rt.Transport | int, params: rt.TransportParams | None) -> rt.Transport:
    """The declared transport, checked together with its params (INVALID_ARGUMENT naming the field)."""
    try:
        transport = rt.Transport(transport)
    except ValueError:
        raise _invalid(f"transport: unknown value {transport}") from None
    if transport == rt.Transport.UNSPECIFIED:
        raise _invalid("transport: must be TRANSPORT_GRPC, TRANSPORT_ROS2 or TRANSPORT_MCP")
    if params is None:
        raise _invalid(f"params: must be set (params.{transport.label} for transport {transport.name})")
    if params.transport != transport:
        raise _invalid(f"params: params.{params.transport.label} does not match transport {transport.name}")
    if isinstance(params, rt.McpParams) and params.input_schema_json:
        try:
            schema = json.loads(params.input_schema_json)
        except ValueError as exc:
            raise _invalid(f"params.mcp.input_schema_json: not valid JSON ({exc})") from None
        if not isinstance(schema, dict):
            raise _invalid("params.mcp.input_schema_json: must be a JSON object")
    return transport


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
    transport: rt.Transport
    endpoint: str
    params: rt.TransportParams
    description: str
    namespace_mismatch: bool


@dataclass
class _Provider:
    id: str
    kind: rt.Kind
    namespace: str
    capability_md_path: str
    capability_md: str
    registration_id: str
    last_heartbeat_ms: int
    hb_mono: float
    pushed_state: rt.LifecycleState | None = None
    state_detail: str = ""
    caps: dict[tuple[str, rt.Transport], _Cap] = field(default_factory=dict)

    @property
    def state(self) -> rt.LifecycleState:
        """robonix rule: never pushed -> INACTIVE once a non-driver capability exists, else REGISTERED."""
        if self.pushed_state is not None:
            return self.pushed_state
        if any(not cid.endswith("/driver") for cid, _ in self.caps):
            return rt.LifecycleState.INACTIVE
        return rt.LifecycleState.REGISTERED


@dataclass
class _Channel:
    channel_id: str
    consumer_id: str
    provider_id: str
    contract_id: str
    transport: rt.Transport
    endpoint: str
    params: rt.TransportParams
    opened_ms: int
    renewed_mono: float = 0.0


_LEGAL_EDGES = {
    (rt.LifecycleState.REGISTERED, rt.LifecycleState.INACTIVE),
    (rt.LifecycleState.INACTIVE, rt.LifecycleState.ACTIVE),
    (rt.LifecycleState.ACTIVE, rt.LifecycleState.INACTIVE),
    (rt.LifecycleState.ERROR, rt.LifecycleState.INACTIVE),
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
        endpoint_check: Callable[[str], str | None] | None = None,
        channel_lease_ms: int = CHANNEL_LEASE_MS,
        max_channels_per_consumer: int = MAX_CHANNELS_PER_CONSUMER,
        max_channels: int = MAX_CHANNELS,
    ) -> None:
        self.catalogue = catalogue if catalogue is not None else Catalogue()
        self.heartbeat_timeout_ms = int(heartbeat_timeout_ms)
        self.gc_after_terminated_ms = int(gc_after_terminated_ms)
        self.channel_lease_ms = int(channel_lease_ms)
        self.max_channels_per_consumer = max(1, int(max_channels_per_consumer))
        self.max_channels = max(1, int(max_channels))
        self._endpoint_check = endpoint_check
        self._clock = clock
        self._wall = wall_clock
        self._lock = threading.Lock()
        self._providers: dict[str, _Provider] = {}
        # Oldest first: renewing a channel moves it to the end, so eviction under the caps takes the stalest.
        self._channels: OrderedDict[str, _Channel] = OrderedDict()
        self._by_consumer: dict[str, OrderedDict[str, None]] = {}
        self.channels_evicted = 0  # dropped by the caps or an expired lease (diagnostics, tests)
        self._by_contract: dict[str, set[str]] = {}
        self._endpoints: dict[tuple[rt.Transport, str], set[str]] = {}

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
            self._pop_channel(c)
        return len(dead)

    def _pop_channel(self, channel_id: str) -> _Channel | None:
        ch = self._channels.pop(channel_id, None)
        if ch is not None:
            mine = self._by_consumer.get(ch.consumer_id)
            if mine is not None:
                mine.pop(channel_id, None)
                if not mine:
                    del self._by_consumer[ch.consumer_id]
        return ch

    def _renew_consumer(self, consumer_id: str, now: float) -> None:
        """A consumer's heartbeat renews the lease of every channel it holds."""
        for cid in self._by_consumer.get(consumer_id, ()):
            ch = self._channels.get(cid)
            if ch is not None:
                ch.renewed_mono = now
                self._channels.move_to_end(cid)

    def _expire_channels(self, now: float) -> int:
        """Drop channels whose lease lapsed (oldest first, so the scan stops at the first live one)."""
        if self.channel_lease_ms <= 0:
            return 0
        limit = now - self.channel_lease_ms / 1000.0
        dead = []
        for cid, ch in self._channels.items():
            if ch.renewed_mono > limit:
                break
            dead.append(cid)
        for cid in dead:
            self._pop_channel(cid)
        self.channels_evicted += len(dead)
        return len(dead)

    def _make_room(self, consumer_id: str, now: float) -> None:
        """Keep the per-consumer and global caps: expired leases go first, then the stalest channel."""
        mine = self._by_consumer.get(consumer_id)
        evicted = 0
        while mine and len(mine) >= self.max_channels_per_consumer:
            self._pop_channel(next(iter(mine)))
            evicted += 1
        if len(self._channels) >= self.max_channels:
            self._expire_channels(now)
        while len(self._channels) >= self.max_channels:
            self._pop_channel(next(iter(self._channels)))
            evicted += 1
        if evicted:
            self.channels_evicted += evicted
            log.debug("channel caps: dropped %d stale channel(s) to open one for %s", evicted, consumer_id)

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

    def _foreign_owners(self, transport: rt.Transport, endpoint: str, me: str) -> list[str]:
        owners = self._endpoints.get((transport, endpoint), ())
        return sorted(o for o in owners if o != me and self._providers[o].state != rt.LifecycleState.TERMINATED)

    # ----------------------------------------------------------------- providers

    def register(
        self, kind: rt.Kind, id: str, namespace: str, capability_md_path: str = "", capability_md: str = "",
        *, may_replace_live: bool = True,
    ) -> str:
        """Register or take over ``id`` (same kind); returns the id (assigned when empty)."""
        return self.register_ex(kind, id, namespace, capability_md_path, capability_md,
                                may_replace_live=may_replace_live)[0]

    def register_ex(
        self, kind: rt.Kind, id: str, namespace: str, capability_md_path: str = "", capability_md: str = "",
        *, may_replace_live: bool = True,
    ) -> tuple[str, str]:
        """:meth:`register`, returning ``(id, registration_id)``.

        Ownership: a live (not TERMINATED) registration is replaced only when ``may_replace_live`` (the
        caller holds the deployment token, or the atlas has none: robonix's takeover); otherwise
        ALREADY_EXISTS names the holder, so a stranger cannot redirect ``nav2``'s consumers."""
        kind = rt.Kind(kind)
        if kind == rt.Kind.UNSPECIFIED:
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
                if not may_replace_live and old.state != rt.LifecycleState.TERMINATED:
                    raise RegistryError(
                        "ALREADY_EXISTS",
                        f"id: {pid!r} is held by a live registration ({old.state.label}); it can be replaced "
                        "once it is TERMINATED or evicted, or by a caller holding the deployment token",
                    )
                log.info("register %s: takeover of registration %s", pid, old.registration_id)
                self._remove(old)
            reg_id = str(uuid.uuid4())
            self._providers[pid] = _Provider(
                id=pid,
                kind=kind,
                namespace=namespace,
                capability_md_path=capability_md_path,
                capability_md=capability_md,
                registration_id=reg_id,
                last_heartbeat_ms=self._now_ms(),
                hb_mono=self._clock(),
            )
        log.info("registered %s %s (namespace %s)", kind.label, pid, namespace)
        return pid, reg_id

    def unregister(self, id: str) -> bool:
        """Idempotent; drops the provider's channels too."""
        with self._lock:
            p = self._providers.get(id)
            if p is None:
                return False
            self._remove(p)
        log.info("unregistered %s", id)
        return True

    def heartbeat(self, id: str, registration_id: str = "") -> None:
        """Only refreshes ``last_heartbeat``; a TERMINATED provider stays TERMINATED (robonix rule).

        With ``registration_id`` (our SDK sends it as metadata) a heartbeat for a registration that was
        replaced meanwhile is refused with FAILED_PRECONDITION instead of keeping the new holder alive,
        so the provider learns it lost its id. Channels the provider holds as a consumer are renewed."""
        with self._lock:
            p = self._get(id)
            if registration_id and registration_id != p.registration_id:
                raise RegistryError(
                    "FAILED_PRECONDITION",
                    f"id: {id!r} was registered again by someone else (registration {p.registration_id}, "
                    f"yours {registration_id[:64]})",
                )
            p.last_heartbeat_ms = self._now_ms()
            p.hb_mono = self._clock()
            self._renew_consumer(id, p.hb_mono)

    def set_state(self, id: str, state: rt.LifecycleState, detail: str = "") -> rt.LifecycleState:
        """Store the pushed state (an unusual edge is logged, not refused); returns the previous one."""
        try:
            state = rt.LifecycleState(state)
        except ValueError:
            raise _invalid(f"state: unknown value {state}") from None
        if state == rt.LifecycleState.UNSPECIFIED:
            raise _invalid("state: must not be STATE_UNSPECIFIED")
        with self._lock:
            p = self._get(id)
            prev = p.state
            if (prev != state and state not in (rt.LifecycleState.ERROR, rt.LifecycleState.TERMINATED)
                    and (prev, state) not in _LEGAL_EDGES):
                log.warning("%s: unusual lifecycle edge %s -> %s (stored)", id, prev.name, state.name)
            p.pushed_state = state
            p.state_detail = detail
            if state == rt.LifecycleState.TERMINATED:
                self._drop_channels(id)
        return prev

    # ----------------------------------------------------------------- capabilities

    def declare(
        self,
        provider_id: str,
        contract_id: str,
        transport: rt.Transport | int,
        endpoint: str,
        params: rt.TransportParams | None,
        description: str = "",
    ) -> str:
        """Declare one (contract, transport) of a provider; returns the endpoint actually stored."""
        if not provider_id:
            raise _invalid("provider_id: must not be empty")
        if not contract_id:
            raise _invalid("contract_id: must not be empty")
        transport = _check_transport_params(transport, params)
        if not endpoint and transport != rt.Transport.ROS2:
            raise _invalid(f"endpoint: must not be empty for transport {transport.name}")
        if transport != rt.Transport.ROS2 and self._endpoint_check is not None:
            problem = self._endpoint_check(endpoint)
            if problem:
                raise _invalid(f"endpoint: {problem}")

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

    def _resolve_endpoint(self, pid: str, contract_id: str, transport: rt.Transport, endpoint: str) -> str:
        if not endpoint:  # only ROS 2 gets here
            for _ in range(MINT_ATTEMPTS):
                ep = mint_ros2_endpoint(contract_id)
                if (transport, ep) not in self._endpoints:
                    return ep
            raise RegistryError("INTERNAL", "endpoint: could not mint a unique ROS 2 name")
        owners = self._foreign_owners(transport, endpoint, pid)
        if not owners:
            return endpoint
        if transport != rt.Transport.ROS2:
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

    def _view(self, p: _Provider, caps: list[_Cap]) -> rt.CapabilityProvider:
        return rt.CapabilityProvider(
            id=p.id,
            kind=p.kind,
            namespace=p.namespace,
            capability_md_path=p.capability_md_path,
            last_heartbeat_ms=p.last_heartbeat_ms,
            state=p.state,
            state_detail=p.state_detail,
            capabilities=[
                rt.Capability(
                    p.id, p.kind, c.contract_id, c.transport, c.params, c.description, c.namespace_mismatch
                )
                for c in caps
            ],
            capability_md=p.capability_md,
            registration_id=p.registration_id,
        )

    def query(
        self,
        kind: rt.Kind | int = rt.Kind.UNSPECIFIED,
        id: str = "",
        contract_id: str = "",
        transport: rt.Transport | int = rt.Transport.UNSPECIFIED,
        namespace_prefix: str = "",
    ) -> list[rt.CapabilityProvider]:
        """robonix Query: empty/UNSPECIFIED (or unknown enum) = no filter; with contract_id, providers
        lacking it are dropped; capabilities are filtered by contract and transport, but a provider is
        kept when only the transport filter empties its list. Sorted by provider id."""
        kind = rt.Kind(kind) if kind in rt.Kind._value2member_map_ else rt.Kind.UNSPECIFIED
        transport = (
            rt.Transport(transport) if transport in rt.Transport._value2member_map_ else rt.Transport.UNSPECIFIED
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
        self, consumer_id: str, provider_id: str, contract_id: str, transport: rt.Transport | int
    ) -> rt.Channel:
        """Open a channel to a declared (contract, transport) of a live provider."""
        for name, value in (
            ("consumer_id", consumer_id),
            ("provider_id", provider_id),
            ("contract_id", contract_id),
        ):
            if not value:
                raise _invalid(f"{name}: must not be empty")
        try:
            transport = rt.Transport(transport)
        except ValueError:
            raise _invalid(f"transport: unknown value {transport}") from None
        if transport == rt.Transport.UNSPECIFIED:
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
            if p.state == rt.LifecycleState.TERMINATED:
                # robonix's atlas opens the channel all the same (its record keeps the endpoints until GC);
                # consumers that want live providers filter on state, as find_capability does.
                log.info("connect %s -> %s: provider is TERMINATED (%s)", consumer_id, provider_id,
                         p.state_detail or "no detail")
            now = self._clock()
            self._make_room(consumer_id, now)
            ch = _Channel(
                channel_id="ch-" + uuid.uuid4().hex,
                consumer_id=consumer_id,
                provider_id=provider_id,
                contract_id=contract_id,
                transport=transport,
                endpoint=cap.endpoint,
                params=cap.params,
                opened_ms=self._now_ms(),
                renewed_mono=now,
            )
            self._channels[ch.channel_id] = ch
            self._by_consumer.setdefault(consumer_id, OrderedDict())[ch.channel_id] = None
            self._renew_consumer(consumer_id, now)  # using the atlas renews the consumer's other channels
        return rt.Channel(ch.channel_id, ch.endpoint, ch.params, provider_id, contract_id, transport)

    def disconnect(self, channel_id: str) -> bool:
        with self._lock:
            return self._pop_channel(channel_id) is not None

    def channel_count(self, provider_id: str | None = None) -> int:
        with self._lock:
            if provider_id is None:
                return len(self._channels)
            return sum(1 for ch in self._channels.values() if provider_id in (ch.provider_id, ch.consumer_id))

    # ----------------------------------------------------------------- contracts

    def query_contract(self, contract_id: str) -> rt.ContractDescriptor | None:
        if not contract_id:
            raise _invalid("contract_id: must not be empty")
        return self.catalogue.get(contract_id)

    def list_contracts(self, prefix: str = "") -> list[rt.ContractDescriptor]:
        return self.catalogue.list(prefix)

    # ----------------------------------------------------------------- eviction & inspection

    def sweep(self) -> tuple[list[str], list[str]]:
        """Mark lapsed providers TERMINATED (dropping their channels) and remove TERMINATED records past
        ``timeout + gc``; drop channels whose lease lapsed. Returns (evicted ids, removed ids). A heartbeat
        timeout of 0 disables the provider part."""
        timeout = self.heartbeat_timeout_ms
        now = self._clock()
        with self._lock:
            expired = self._expire_channels(now)
        if expired:
            log.info("%d channel lease(s) lapsed (> %d ms without renewal)", expired, self.channel_lease_ms)
        if timeout <= 0:
            return [], []
        evicted: list[str] = []
        removed: list[str] = []
        with self._lock:
            for p in list(self._providers.values()):
                idle_ms = (now - p.hb_mono) * 1000.0
                if p.state == rt.LifecycleState.TERMINATED:
                    if idle_ms > timeout + self.gc_after_terminated_ms:
                        self._remove(p)
                        removed.append(p.id)
                elif idle_ms > timeout:
                    p.pushed_state = rt.LifecycleState.TERMINATED
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
                        "params": rt.params_to_dict(c.params),
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
            newest = list(self._channels.values())[-MAX_SNAPSHOT_CHANNELS:]
            channels_total = len(self._channels)
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
                for ch in newest
            ]
        return {
            "providers": providers,
            "capabilities": caps,
            "channels": channels,
            "channels_total": channels_total,
            "channel_lease_ms": self.channel_lease_ms,
            "contracts": len(self.catalogue),
            "heartbeat_timeout_ms": self.heartbeat_timeout_ms,
            "now_ms": self._now_ms(),
        }


__all__ = [
    "Registry",
    "RegistryError",
    "is_valid_ros2_name",
    "mint_ros2_endpoint",
    "rewrite_ros2_endpoint",
]
