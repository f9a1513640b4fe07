"""Typed client of the atlas registry (``robonix.atlas.Atlas``), with robonix's SDK names.

``ATLAS`` is the module-level instance every provider uses; it resolves ``$ROBONIX_ATLAS`` (default
``127.0.0.1:50051``) and connects on first use, so importing the SDK never touches the network.
Arguments naming a kind, transport or state accept the enum, its int, or a string (``"ros2"``).
"""

from __future__ import annotations

import json
import logging
import os
import threading
from collections.abc import Callable
from typing import Any

import grpc

from robonix_api import auth
from robonix_api.proto_gen import atlas_pb2, atlas_pb2_grpc
from robonix_api.types import (
    Capability,
    CapabilityProvider,
    Channel,
    ContractDescriptor,
    Kind,
    LifecycleState,
    Transport,
    TransportParams,
    default_params,
    params_from_pb,
    params_to_pb,
)

log = logging.getLogger(__name__)

DEFAULT_ADDRESS = "127.0.0.1:50051"
#: Per-call deadline; generous because a loaded CI box can stall a loopback call for a while.
DEFAULT_TIMEOUT_S = 10.0
#: Trailing metadata of our atlas's Register answers; sent back on Heartbeat (see atlas.server).
REGISTRATION_ID_KEY = "robonix-registration-id"


def default_address() -> str:
    """$ROBONIX_ATLAS, else 127.0.0.1:50051: where every client looks for the atlas unless told."""
    return os.environ.get("ROBONIX_ATLAS", "").strip() or DEFAULT_ADDRESS


class HeartbeatHandle(threading.Thread):
    """A background heartbeat loop; ``stop()`` ends it (and joins the thread).

    It is the (daemon) ``threading.Thread`` itself, which is what robonix-api's ``start_heartbeat``
    returns; ``stop()``, ``beats`` and ``on_not_found`` are this SDK's additions."""

    def __init__(
        self,
        client: AtlasClient,
        id: str,
        period_s: float,
        on_not_found: Callable[[], None] | None,
    ) -> None:
        self.id = id
        self.period_s = float(period_s)
        self._client = client
        self._on_not_found = on_not_found
        self._stopping = threading.Event()
        self.beats = 0  # successful heartbeats, handy for tests and diagnostics
        super().__init__(name=f"robonix-hb-{id}", daemon=True)
        self.start()

    @property
    def running(self) -> bool:
        """Whether the heartbeat thread still runs (it stops on ``stop()`` or when the atlas forgets us)."""
        return self.is_alive()

    def run(self) -> None:
        """Send a heartbeat every ``period_s`` until stopped; log an unreachable atlas once, not every beat."""
        unavailable_logged = False
        while not self._stopping.wait(self.period_s):
            try:
                self._client.heartbeat_or_raise(self.id)
                self.beats += 1
                if unavailable_logged:
                    log.info("heartbeat %s: atlas %s reachable again", self.id, self._client.address)
                unavailable_logged = False
            except grpc.RpcError as exc:
                code = exc.code() if hasattr(exc, "code") else None
                if code in (grpc.StatusCode.NOT_FOUND, grpc.StatusCode.FAILED_PRECONDITION):
                    if code == grpc.StatusCode.NOT_FOUND:
                        log.warning("heartbeat %s: atlas does not know us (restarted?)", self.id)
                    else:
                        log.error("heartbeat %s: OUR REGISTRATION WAS REPLACED by another Register of this id "
                                  "(%s)", self.id, exc.details() if hasattr(exc, "details") else exc)
                    if self._on_not_found is not None:
                        try:
                            self._on_not_found()
                        except Exception:
                            log.exception("heartbeat %s: on_not_found callback failed", self.id)
                elif not unavailable_logged:
                    log.warning(
                        "heartbeat %s: atlas %s: %s (will keep trying)", self.id, self._client.address, code
                    )
                    unavailable_logged = True
            except Exception:
                log.exception("heartbeat %s: unexpected error", self.id)

    def stop(self, timeout: float = 5.0) -> None:
        """Stop beating and wait up to ``timeout`` s for the thread (not when called from the thread itself)."""
        self._stopping.set()
        if self is not threading.current_thread():
            self.join(timeout)


class AtlasClient:
    """Thread-safe, lazily connected atlas client. Errors surface as ``grpc.RpcError`` (status codes as
    in the spec) except where noted; argument parsing errors are ``ValueError``."""

    def __init__(self, address: str | None = None) -> None:
        self._address = address
        self._lock = threading.Lock()
        self._channel: grpc.Channel | None = None
        self._raw_channel: grpc.Channel | None = None
        self._stub: atlas_pb2_grpc.AtlasStub | None = None
        self.timeout = DEFAULT_TIMEOUT_S
        #: provider id -> registration id our atlas answered with (empty from robonix's atlas)
        self.registration_ids: dict[str, str] = {}

    # ----------------------------------------------------------------- connection

    @property
    def address(self) -> str:
        """The atlas address (``$ROBONIX_ATLAS`` is read at first use when none was given)."""
        return self._address or default_address()

    @property
    def stub(self) -> atlas_pb2_grpc.AtlasStub:
        """The raw generated stub (connects on first access)."""
        stub = self._stub
        if stub is not None:
            return stub
        with self._lock:
            if self._stub is None:
                if self._address is None:
                    self._address = default_address()
                # The deployment token ($ROBONIX_DEPLOY_TOKEN) rides on every call when set (robonix_api.auth).
                self._raw_channel = grpc.insecure_channel(self._address, options=[("grpc.enable_http_proxy", 0)])
                self._channel = grpc.intercept_channel(self._raw_channel, auth.TokenClientInterceptor())
                self._stub = atlas_pb2_grpc.AtlasStub(self._channel)
            return self._stub

    def close(self) -> None:
        """Close the channel; the client reconnects lazily if used again."""
        with self._lock:
            channel, self._raw_channel, self._channel, self._stub = self._raw_channel, None, None, None
        if channel is not None:
            channel.close()

    def __enter__(self) -> AtlasClient:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def wait_ready(self, timeout: float = 10.0) -> None:
        """Block until the atlas channel is connected; ``grpc.FutureTimeoutError`` otherwise."""
        self.stub  # noqa: B018 (creates the channel)
        assert self._raw_channel is not None
        grpc.channel_ready_future(self._raw_channel).result(timeout=timeout)

    # ----------------------------------------------------------------- providers

    def register(
        self,
        kind: Kind | int | str,
        id: str,
        namespace: str,
        capability_md_path: str = "",
        capability_md: str = "",
    ) -> str:
        """Register (or take over) a provider; returns its id (assigned by the atlas when empty)."""
        k = Kind.parse(kind)
        rpc = {
            Kind.PRIMITIVE: self.stub.RegisterPrimitive,
            Kind.SERVICE: self.stub.RegisterService,
            Kind.SKILL: self.stub.RegisterSkill,
        }.get(k)
        if rpc is None:
            raise ValueError("kind: must be primitive, service or skill")
        req = atlas_pb2.RegisterRequest(
            id=id, namespace=namespace, capability_md_path=capability_md_path, capability_md=capability_md
        )
        resp, call = rpc.with_call(req, timeout=self.timeout)
        reg_id = next((str(v) for k, v in call.trailing_metadata() or () if k == REGISTRATION_ID_KEY), "")
        self.registration_ids[resp.id] = reg_id
        return resp.id

    def register_primitive(
        self, id: str, namespace: str, capability_md_path: str = "", capability_md: str = ""
    ) -> str:
        """``register`` with kind PRIMITIVE (robonix-api's name); returns the registration id."""
        return self.register(Kind.PRIMITIVE, id, namespace, capability_md_path, capability_md)

    def register_service(
        self, id: str, namespace: str, capability_md_path: str = "", capability_md: str = ""
    ) -> str:
        """``register`` with kind SERVICE (robonix-api's name); returns the registration id."""
        return self.register(Kind.SERVICE, id, namespace, capability_md_path, capability_md)

    def register_skill(
        self, id: str, namespace: str, capability_md_path: str = "", capability_md: str = ""
    ) -> str:
        """``register`` with kind SKILL (robonix-api's name); returns the registration id."""
        return self.register(Kind.SKILL, id, namespace, capability_md_path, capability_md)

    def unregister(self, id: str) -> bool:
        """Remove provider ``id`` and its channels; False when the atlas did not know it."""
        return self.stub.Unregister(atlas_pb2.UnregisterRequest(id=id), timeout=self.timeout).was_present

    def heartbeat(self, id: str) -> None:
        """Raises ``grpc.RpcError`` (NOT_FOUND when the atlas does not know ``id``)."""
        self.heartbeat_or_raise(id)

    def heartbeat_or_raise(self, id: str) -> None:
        """One heartbeat, errors raised (``ATLAS.heartbeat`` swallows them, as robonix-api does).

        When this client registered ``id`` it sends the registration id along, and our atlas answers
        FAILED_PRECONDITION once somebody else has registered ``id`` since (the registration was replaced)."""
        reg_id = self.registration_ids.get(id, "")
        md = ((REGISTRATION_ID_KEY, reg_id),) if reg_id else None
        self.stub.Heartbeat(atlas_pb2.HeartbeatRequest(id=id), timeout=self.timeout, metadata=md)

    def set_state(self, id: str, state: LifecycleState | int | str, detail: str = "") -> LifecycleState:
        """Push a lifecycle state; returns the previous one."""
        req = atlas_pb2.SetLifecycleStateRequest(id=id, state=int(LifecycleState.parse(state)), detail=detail)
        prev = self.stub.SetLifecycleState(req, timeout=self.timeout).previous_state
        return (
            LifecycleState(prev) if prev in LifecycleState._value2member_map_ else LifecycleState.UNSPECIFIED
        )

    def start_heartbeat(
        self, id: str, period_s: float = 30.0, on_not_found: Callable[[], None] | None = None
    ) -> HeartbeatHandle:
        """Heartbeat ``id`` every ``period_s`` on a daemon thread. ``on_not_found`` runs when the atlas
        answers NOT_FOUND (it restarted): the SDK re-registers and re-declares there. An unreachable
        atlas is logged once and retried every period."""
        if period_s <= 0:
            raise ValueError("period_s: must be > 0")
        return HeartbeatHandle(self, id, period_s, on_not_found)

    # ----------------------------------------------------------------- capabilities

    def declare_capability(
        self,
        provider_id: str,
        contract_id: str,
        transport: Transport | int | str,
        endpoint: str | Transport | int,
        params: TransportParams | None = None,
        description: str = "",
    ) -> str:
        """Declare a capability; returns the endpoint the atlas stored (a ROS 2 name may be minted or
        rewritten on collision). Omitted params become the transport's default params.

        robonix-api's order is ``(provider_id, contract_id, transport, endpoint)``; this SDK's earlier
        order ``(provider_id, contract_id, endpoint, transport)`` keeps working: the transport is the
        argument that is a :class:`Transport`, an int, or a transport name (``"ros2"``, ``"grpc"``,
        ``"mcp"``), and an endpoint never is one. ALREADY_EXISTS answers return ``endpoint`` as
        robonix-api does.
        """
        t, endpoint = split_transport_endpoint(transport, endpoint)
        if params is None:
            params = default_params(t)
        req = atlas_pb2.DeclareCapabilityRequest(
            provider_id=provider_id,
            contract_id=contract_id,
            transport=int(t),
            endpoint=endpoint,
            description=description,
        )
        if params is not None:
            params_to_pb(params, req.params)
        try:
            return self.stub.DeclareCapability(req, timeout=self.timeout).endpoint or endpoint
        except grpc.RpcError as exc:
            if exc.code() == grpc.StatusCode.ALREADY_EXISTS:
                return endpoint
            raise

    def query(
        self,
        *,
        kind: Kind | int | str | None = Kind.UNSPECIFIED,
        id: str = "",
        contract_id: str = "",
        namespace_prefix: str = "",
        transport: Transport | int | str | None = Transport.UNSPECIFIED,
    ) -> list[CapabilityProvider]:
        """Raw Query (server-side filters only; TERMINATED providers included)."""
        req = atlas_pb2.QueryRequest(
            kind=int(Kind.parse(kind)),
            id=id,
            contract_id=contract_id,
            transport=int(Transport.parse(transport)),
            namespace_prefix=namespace_prefix,
        )
        resp = self.stub.Query(req, timeout=self.timeout)
        return [CapabilityProvider.from_pb(p) for p in resp.providers]

    def query_primitives(self, *, id: str = "", contract_id: str = "", namespace_prefix: str = "",
                         transport: Transport | int | str | None = Transport.UNSPECIFIED) -> list[CapabilityProvider]:
        """``query`` restricted to primitives (robonix-api's name)."""
        return self.query(kind=Kind.PRIMITIVE, id=id, contract_id=contract_id,
                          namespace_prefix=namespace_prefix, transport=transport)

    def query_services(self, *, id: str = "", contract_id: str = "", namespace_prefix: str = "",
                       transport: Transport | int | str | None = Transport.UNSPECIFIED) -> list[CapabilityProvider]:
        """``query`` restricted to services (robonix-api's name)."""
        return self.query(kind=Kind.SERVICE, id=id, contract_id=contract_id,
                          namespace_prefix=namespace_prefix, transport=transport)

    def query_skills(self, *, id: str = "", contract_id: str = "", namespace_prefix: str = "",
                     transport: Transport | int | str | None = Transport.UNSPECIFIED) -> list[CapabilityProvider]:
        """``query`` restricted to skills (robonix-api's name)."""
        return self.query(kind=Kind.SKILL, id=id, contract_id=contract_id,
                          namespace_prefix=namespace_prefix, transport=transport)

    def find_capability(
        self,
        *,
        contract_id: str = "",
        transport: Transport | int | str | None = Transport.UNSPECIFIED,
        provider_kind: Kind | int | str | None = Kind.UNSPECIFIED,
        provider_id: str | None = "",
        namespace_prefix: str = "",
    ) -> list[Capability]:
        """Live capabilities matching the filters: Query, then exact contract (when given) and transport,
        TERMINATED providers left out. An empty ``contract_id`` lists every live capability."""
        t = Transport.parse(transport)
        out: list[Capability] = []
        for p in self.query(
            kind=provider_kind,
            id=provider_id or "",
            contract_id=contract_id,
            transport=t,
            namespace_prefix=namespace_prefix,
        ):
            if p.state == LifecycleState.TERMINATED:
                continue
            for cap in p.capabilities:
                if (not contract_id or cap.contract_id == contract_id) and (not t or cap.transport == t):
                    out.append(cap)
        return out

    def find_unique_capability(
        self,
        *,
        contract_id: str,
        transport: Transport | int | str | None = Transport.UNSPECIFIED,
        provider_kind: Kind | int | str | None = Kind.UNSPECIFIED,
        provider_id: str | None = "",
        namespace_prefix: str = "",
    ) -> Capability:
        """Exactly one match of ``find_capability(...)``; ValueError naming the contract and the
        candidates otherwise (pin one with ``provider_id``)."""
        filters: dict[str, Any] = dict(contract_id=contract_id, transport=transport, provider_kind=provider_kind,
                                       provider_id=provider_id, namespace_prefix=namespace_prefix)
        caps = self.find_capability(**filters)
        if len(caps) == 1:
            return caps[0]
        cid = filters.get("contract_id", "")
        extra = ", ".join(
            f"{k}={v!r}" for k, v in filters.items() if k != "contract_id" and v
        )
        where = f" ({extra})" if extra else ""
        if not caps:
            raise ValueError(f"no live provider offers contract {cid!r}{where}")
        cands = ", ".join(sorted(f"{c.provider_id} [{c.transport.label}]" for c in caps))
        raise ValueError(
            f"contract {cid!r}{where} is offered by {len(caps)} candidates: {cands}; pin one with provider_id"
        )

    def connect_capability(
        self, *, consumer_id: str, provider_id: str, contract_id: str, transport: Transport | int | str
    ) -> Channel:
        """Open a channel; the returned Channel closes itself on ``close()`` or leaving a ``with``."""
        t = Transport.parse(transport)
        req = atlas_pb2.ConnectCapabilityRequest(
            consumer_id=consumer_id, provider_id=provider_id, contract_id=contract_id, transport=int(t)
        )
        resp = self.stub.ConnectCapability(req, timeout=self.timeout)
        return Channel(
            channel_id=resp.channel_id,
            endpoint=resp.endpoint,
            params=params_from_pb(resp.params) if resp.HasField("params") else None,
            provider_id=provider_id,
            contract_id=contract_id,
            transport=t,
            _client=self,
        )

    def disconnect(self, channel_id: str) -> bool:
        """Close channel ``channel_id`` at the atlas; False when it was not open."""
        req = atlas_pb2.DisconnectCapabilityRequest(channel_id=channel_id)
        return self.stub.DisconnectCapability(req, timeout=self.timeout).was_open

    def disconnect_capability(self, channel_id: str) -> bool:
        """robonix-api's name for :meth:`disconnect`."""
        return self.disconnect(channel_id)

    # ----------------------------------------------------------------- contracts & inspection

    def query_contract(self, contract_id: str) -> ContractDescriptor | None:
        """The catalogue entry of ``contract_id``, or None when the atlas has no such contract."""
        resp = self.stub.QueryContract(
            atlas_pb2.QueryContractRequest(contract_id=contract_id), timeout=self.timeout
        )
        return ContractDescriptor.from_pb(resp.contract) if resp.found else None

    def list_contracts(self, namespace_prefix: str = "") -> list[ContractDescriptor]:
        """Catalogue entries whose id starts with ``namespace_prefix`` (all for "")."""
        resp = self.stub.ListContracts(
            atlas_pb2.ListContractsRequest(namespace_prefix=namespace_prefix), timeout=self.timeout
        )
        return [ContractDescriptor.from_pb(c) for c in resp.contracts]

    def inspect(self) -> dict[str, Any]:
        """The atlas's InspectAtlas snapshot (providers, capabilities, channels) as parsed JSON."""
        return json.loads(self.stub.InspectAtlas(atlas_pb2.InspectAtlasRequest(), timeout=self.timeout).json)


def split_transport_endpoint(a: Any, b: Any) -> tuple[Transport, str]:
    """``(transport, endpoint)`` from two arguments given in either order (see ``declare_capability``)."""
    a_is, b_is = _looks_like_transport(a), _looks_like_transport(b)
    if a_is and not b_is:
        return Transport.parse(a), str(b)
    if b_is and not a_is:
        return Transport.parse(b), str(a)
    raise ValueError(f"transport/endpoint: cannot tell which of {a!r} and {b!r} is the transport "
                     "(pass transport=... and endpoint=... by keyword)")


def _looks_like_transport(value: Any) -> bool:
    if isinstance(value, Transport) or (isinstance(value, int) and not isinstance(value, bool)):
        return True
    if isinstance(value, str):
        name = value.strip().upper().replace("-", "_").removeprefix("TRANSPORT_")
        return name in _TRANSPORT_NAMES or (name.isdigit() and int(name) in Transport._value2member_map_)
    return False


_TRANSPORT_NAMES = frozenset(Transport.__members__) | {"ROS"}


class RobonixAtlas(AtlasClient):
    """The ``ATLAS`` singleton: an :class:`AtlasClient` whose calls fail the way robonix-api's do.

    robonix-api's ``ATLAS`` logs and returns a neutral value where this SDK's client raises:
    ``heartbeat`` -> None, ``unregister``/``disconnect_capability`` -> False, ``query*`` /
    ``find_capability``/``list_contracts`` -> [], ``query_contract`` -> None, ``inspect`` -> {}.
    Code that wants the errors (the SDK's own providers, rbnx) uses :class:`AtlasClient`.
    Registration, ``declare_capability`` and ``connect_capability`` raise in both.
    """

    def __init__(self, endpoint: str | None = None) -> None:
        super().__init__(endpoint)

    def heartbeat(self, id: str) -> None:
        """Like robonix-api: log a failed heartbeat instead of raising."""
        try:
            self.heartbeat_or_raise(id)
        except grpc.RpcError as exc:
            log.debug("heartbeat(%s): %s", id, exc)

    def unregister(self, id: str) -> bool:
        """Like robonix-api: False (logged) instead of raising when the atlas call fails."""
        try:
            return super().unregister(id)
        except grpc.RpcError as exc:
            log.debug("unregister(%s): %s", id, exc)
            return False

    def query(
        self,
        *,
        kind: Kind | int | str | None = Kind.UNSPECIFIED,
        id: str = "",
        contract_id: str = "",
        namespace_prefix: str = "",
        transport: Transport | int | str | None = Transport.UNSPECIFIED,
    ) -> list[CapabilityProvider]:
        """Like robonix-api: [] (logged) instead of raising when the atlas call fails."""
        try:
            return super().query(kind=kind, id=id, contract_id=contract_id, transport=transport,
                                 namespace_prefix=namespace_prefix)
        except grpc.RpcError as exc:
            log.warning("Query(kind=%r, id=%r, contract=%r): %s", kind, id, contract_id, exc)
            return []

    def disconnect(self, channel_id: str) -> bool:
        """Like robonix-api: False (logged) instead of raising when the atlas call fails."""
        try:
            return super().disconnect(channel_id)
        except grpc.RpcError as exc:
            log.debug("DisconnectCapability(%s): %s", channel_id, exc)
            return False

    def query_contract(self, contract_id: str) -> ContractDescriptor | None:
        """Like robonix-api: None (logged) instead of raising when the atlas call fails."""
        try:
            return super().query_contract(contract_id)
        except grpc.RpcError as exc:
            log.debug("QueryContract(%s): %s", contract_id, exc)
            return None

    def list_contracts(self, namespace_prefix: str = "") -> list[ContractDescriptor]:
        """Like robonix-api: [] (logged) instead of raising when the atlas call fails."""
        try:
            return super().list_contracts(namespace_prefix)
        except grpc.RpcError as exc:
            log.warning("ListContracts(prefix=%r): %s", namespace_prefix, exc)
            return []

    def inspect(self) -> dict[str, Any]:
        """Like robonix-api: {} (logged) instead of raising when the atlas call or its JSON fails."""
        try:
            return super().inspect()
        except (grpc.RpcError, ValueError) as exc:
            log.debug("InspectAtlas: %s", exc)
            return {}


#: The default client. It reads ``$ROBONIX_ATLAS`` when it first connects, not at import.
ATLAS: RobonixAtlas = RobonixAtlas()

__all__ = ["ATLAS", "AtlasClient", "HeartbeatHandle", "RobonixAtlas", "default_address", "split_transport_endpoint"]
