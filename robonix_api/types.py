"""Plain Python mirrors of the atlas wire types (``robonix.atlas``), shared by the SDK and the atlas.

Callers work with these dataclasses and IntEnums instead of protobuf messages, so they get type hints,
value equality and friendly argument parsing (``"ros2"``, ``2`` and ``Transport.ROS2`` all mean the same
transport). ``from_pb``/``to_pb`` are the only places that know the wire layout.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import IntEnum
from typing import TYPE_CHECKING, Any, Union

from robonix_api.proto_gen import atlas_pb2

if TYPE_CHECKING:  # pragma: no cover
    from robonix_api.atlas_client import AtlasClient


class _WireEnum(IntEnum):
    """IntEnum with a lenient ``parse`` accepting the enum, its int, or a name in several spellings."""

    @classmethod
    def _prefix(cls) -> str:
        return ""

    @classmethod
    def _aliases(cls) -> dict[str, str]:
        return {}

    @classmethod
    def parse(cls, value: Any) -> Any:
        """``None``/``""`` -> UNSPECIFIED; ints must be a known value; strings match case-insensitively
        with or without the proto prefix (``"ros2"``, ``"ROS2"``, ``"TRANSPORT_ROS2"``)."""
        if value is None or value == "":
            return cls(0)
        if isinstance(value, cls):
            return value
        if isinstance(value, bool):
            raise ValueError(f"{cls.__name__}: {value!r} is not a valid value")
        if isinstance(value, int):
            try:
                return cls(value)
            except ValueError:
                raise ValueError(f"{cls.__name__}: unknown value {value}") from None
        if isinstance(value, str):
            name = value.strip().upper().replace("-", "_")
            prefix = cls._prefix()
            if prefix and name.startswith(prefix):
                name = name[len(prefix) :]
            name = cls._aliases().get(name, name)
            if name in cls.__members__:
                return cls.__members__[name]
            if name.isdigit():
                return cls.parse(int(name))
            choices = ", ".join(m.lower() for m in cls.__members__ if m != "UNSPECIFIED")
            raise ValueError(f"{cls.__name__}: unknown name {value!r} (one of {choices})")
        raise TypeError(f"{cls.__name__}: cannot interpret {type(value).__name__} {value!r}")

    @property
    def label(self) -> str:
        """Lower-case short name, e.g. ``ros2``, ``primitive``, ``active``."""
        return self.name.lower()

    def __eq__(self, other: object) -> bool:
        """Also equal to its lower-case label, so ``provider.state == "active"`` (this SDK's earlier
        string states) keeps working now that ``state`` is a :class:`LifecycleState` as in robonix-api."""
        if isinstance(other, str):
            return other.strip().lower() == self.name.lower()
        return int.__eq__(self, other)

    def __ne__(self, other: object) -> bool:
        eq = self.__eq__(other)
        return eq if eq is NotImplemented else not eq

    __hash__ = IntEnum.__hash__


class Kind(_WireEnum):
    """What a provider is: primitive (hardware), service or skill (wire values of atlas.proto)."""
    UNSPECIFIED = 0
    PRIMITIVE = 1
    SERVICE = 2
    SKILL = 3

    @classmethod
    def _prefix(cls) -> str:
        return "KIND_"


class Transport(_WireEnum):
    """How a capability is reached: gRPC, ROS 2 (DDS topic) or MCP."""
    UNSPECIFIED = 0
    GRPC = 1
    ROS2 = 2
    MCP = 3

    @classmethod
    def _prefix(cls) -> str:
        return "TRANSPORT_"

    @classmethod
    def _aliases(cls) -> dict[str, str]:
        return {"ROS": "ROS2"}  # robonix-api accepts "ros" too


class LifecycleState(_WireEnum):
    """A provider's lifecycle state as the atlas stores it."""
    UNSPECIFIED = 0
    REGISTERED = 1
    INACTIVE = 2
    ACTIVE = 3
    ERROR = 4
    TERMINATED = 5

    @classmethod
    def _prefix(cls) -> str:
        return "STATE_"


def _enum_or_raw(enum: type[_WireEnum], value: int) -> Any:
    """Wire ints the enum does not know (a newer peer) are kept as UNSPECIFIED rather than crashing."""
    try:
        return enum(value)
    except ValueError:
        return enum(0)


# --------------------------------------------------------------------------- transport params


@dataclass(frozen=True)
class GrpcParams:
    """Where a gRPC capability is served: proto file, service and method."""
    proto_file: str = "robonix_contracts.proto"
    service_name: str = ""
    method: str = ""

    transport = Transport.GRPC


@dataclass(frozen=True)
class Ros2Params:
    """A ROS 2 capability's QoS profile (the topic is its endpoint)."""
    qos_profile: str = ""

    transport = Transport.ROS2


@dataclass(frozen=True)
class McpParams:
    """An MCP tool's JSON input schema."""
    input_schema_json: str = "{}"

    transport = Transport.MCP


TransportParams = Union[GrpcParams, Ros2Params, McpParams]  # noqa: UP007 (runtime alias)


def params_from_pb(pb: atlas_pb2.TransportParams | None) -> TransportParams | None:
    """The set oneof branch as a dataclass; ``None`` when no branch is set."""
    if pb is None:
        return None
    which = pb.WhichOneof("kind")
    if which == "grpc":
        return GrpcParams(pb.grpc.proto_file, pb.grpc.service_name, pb.grpc.method)
    if which == "ros2":
        return Ros2Params(pb.ros2.qos_profile)
    if which == "mcp":
        return McpParams(pb.mcp.input_schema_json)
    return None


def params_to_pb(params: TransportParams | None, out: atlas_pb2.TransportParams | None = None) -> Any:
    """Fill (or create) a ``TransportParams`` message; ``None`` leaves the oneof unset."""
    msg = out if out is not None else atlas_pb2.TransportParams()
    if isinstance(params, GrpcParams):
        msg.grpc.proto_file = params.proto_file
        msg.grpc.service_name = params.service_name
        msg.grpc.method = params.method
    elif isinstance(params, Ros2Params):
        msg.ros2.qos_profile = params.qos_profile
    elif isinstance(params, McpParams):
        msg.mcp.input_schema_json = params.input_schema_json
    elif params is not None:
        raise TypeError(f"params: expected GrpcParams, Ros2Params or McpParams, got {type(params).__name__}")
    return msg


def params_to_dict(params: TransportParams | None) -> dict[str, Any] | None:
    """JSON-friendly form ``{"ros2": {"qos_profile": "reliable"}}`` (used by InspectAtlas)."""
    if params is None:
        return None
    return {params.transport.label: dict(params.__dict__)}


def default_params(transport: Transport) -> TransportParams | None:
    """Default params of the right branch, so a caller may omit them (robonix-api sends the same:
    ``proto_file="robonix_contracts.proto"`` for gRPC, ``"{}"`` as MCP input schema)."""
    return {Transport.GRPC: GrpcParams(), Transport.ROS2: Ros2Params(), Transport.MCP: McpParams()}.get(
        transport
    )


# --------------------------------------------------------------------------- providers & capabilities


@dataclass
class Capability:
    """One declared (contract, transport) of a provider. The wire form carries no endpoint: a consumer
    gets it from ConnectCapability."""

    provider_id: str
    provider_kind: Kind
    contract_id: str
    transport: Transport
    params: TransportParams | None = None
    description: str = ""
    namespace_mismatch: bool = False

    def __post_init__(self) -> None:
        # robonix-api's positional order is (..., transport, description, params): tell it apart by type.
        if isinstance(self.params, str):
            desc, params = self.params, self.description
            self.params = None if isinstance(params, str) else params
            self.description = desc

    @classmethod
    def from_pb(cls, pb: atlas_pb2.Capability) -> Capability:
        """From the atlas's protobuf record (unknown enum values kept as ints)."""
        return cls(
            provider_id=pb.provider_id,
            provider_kind=_enum_or_raw(Kind, pb.provider_kind),
            contract_id=pb.contract_id,
            transport=_enum_or_raw(Transport, pb.transport),
            params=params_from_pb(pb.params) if pb.HasField("params") else None,
            description=pb.description,
            namespace_mismatch=pb.namespace_mismatch,
        )

    def to_pb(self, out: atlas_pb2.Capability | None = None) -> atlas_pb2.Capability:
        """As the atlas's protobuf record (into ``out`` when given)."""
        msg = out if out is not None else atlas_pb2.Capability()
        msg.provider_id = self.provider_id
        msg.provider_kind = int(self.provider_kind)
        msg.contract_id = self.contract_id
        msg.transport = int(self.transport)
        if self.params is not None:
            params_to_pb(self.params, msg.params)
        msg.description = self.description
        msg.namespace_mismatch = self.namespace_mismatch
        return msg


@dataclass
class CapabilityProvider:
    """A registered provider as the atlas reports it: id, kind, namespace, state and capabilities."""
    id: str
    kind: Kind
    namespace: str
    capability_md_path: str = ""
    last_heartbeat_ms: int = 0
    state: LifecycleState = LifecycleState.UNSPECIFIED
    state_detail: str = ""
    capabilities: list[Capability] = field(default_factory=list)
    capability_md: str = ""
    registration_id: str = ""

    @classmethod
    def from_pb(cls, pb: atlas_pb2.CapabilityProvider) -> CapabilityProvider:
        """From the atlas's protobuf record (unknown enum values kept as ints)."""
        return cls(
            id=pb.id,
            kind=_enum_or_raw(Kind, pb.kind),
            namespace=pb.namespace,
            capability_md_path=pb.capability_md_path,
            last_heartbeat_ms=pb.last_heartbeat_ms,
            state=_enum_or_raw(LifecycleState, pb.state),
            state_detail=pb.state_detail,
            capabilities=[Capability.from_pb(c) for c in pb.capabilities],
            capability_md=pb.capability_md,
            registration_id=getattr(pb, "registration_id", ""),
        )

    def to_pb(self, out: atlas_pb2.CapabilityProvider | None = None) -> atlas_pb2.CapabilityProvider:
        """As the atlas's protobuf record (into ``out`` when given)."""
        msg = out if out is not None else atlas_pb2.CapabilityProvider()
        msg.id = self.id
        msg.kind = int(self.kind)
        msg.namespace = self.namespace
        msg.capability_md_path = self.capability_md_path
        msg.last_heartbeat_ms = self.last_heartbeat_ms
        msg.state = int(self.state)
        msg.state_detail = self.state_detail
        for cap in self.capabilities:
            cap.to_pb(msg.capabilities.add())
        msg.capability_md = self.capability_md
        msg.registration_id = self.registration_id
        return msg


@dataclass
class Channel:
    """An open consumer->provider channel. Close it (or use ``with``) once the endpoint has been read,
    as robonix's navigation and mapping packages do."""

    channel_id: str
    endpoint: str
    params: TransportParams | None = None
    provider_id: str = ""
    contract_id: str = ""
    transport: Transport = Transport.UNSPECIFIED
    _client: AtlasClient | None = field(default=None, repr=False, compare=False)
    _closed: bool = field(default=False, repr=False, compare=False)
    _closer: Any = field(default=None, repr=False, compare=False)

    def __post_init__(self) -> None:
        # robonix-api's positional order is (provider_id, contract_id, transport, endpoint, channel_id,
        # params): its third argument is a Transport where ours is params, so the two can be told apart.
        if isinstance(self.params, int):
            pid, cid, transport, endpoint, chid, params = (self.channel_id, self.endpoint, self.params,
                                                           self.provider_id, self.contract_id, self.transport)
            self.provider_id, self.contract_id, self.endpoint, self.channel_id = pid, cid, endpoint, chid
            self.transport = Transport.parse(transport)
            self.params = None if isinstance(params, int) else params
        if not isinstance(self.transport, Transport):
            self.transport = Transport.parse(self.transport)
        if self._client is not None and not hasattr(self._client, "disconnect"):  # robonix-api's 7th: _closer
            self._closer, self._client = self._client, None

    @property
    def qos_profile(self) -> str:
        """Shortcut for ROS 2 channels (``""`` otherwise)."""
        return self.params.qos_profile if isinstance(self.params, Ros2Params) else ""

    def close(self) -> bool:
        """Disconnect once; later calls are no-ops. Returns whether the atlas still had it open.

        A channel built by hand may carry robonix-api's ``_closer(channel_id)`` instead of a client;
        as in robonix-api, a failing closer is ignored (closing is best effort)."""
        if self._closed:
            return False
        if self._client is not None:
            self._closed = True
            return self._client.disconnect(self.channel_id)
        if self._closer is None:
            return False
        self._closed = True
        try:
            return bool(self._closer(self.channel_id))
        except Exception:  # best effort, as robonix-api
            return False

    def __enter__(self) -> Channel:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


# --------------------------------------------------------------------------- contracts


@dataclass(frozen=True)
class FieldSpec:
    """One field of a contract's message: ``type_name`` is a ROS primitive (``float64``) or ``pkg/Name``."""

    name: str
    type_name: str
    is_primitive: bool = False
    is_array: bool = False
    array_size: int = 0

    @classmethod
    def from_pb(cls, pb: atlas_pb2.FieldSpec) -> FieldSpec:
        """From the atlas's protobuf record."""
        return cls(pb.name, pb.type_name, pb.is_primitive, pb.is_array, pb.array_size)

    def to_pb(self, out: atlas_pb2.FieldSpec | None = None) -> atlas_pb2.FieldSpec:
        """As the atlas's protobuf record (into ``out`` when given)."""
        msg = out if out is not None else atlas_pb2.FieldSpec()
        msg.name = self.name
        msg.type_name = self.type_name
        msg.is_primitive = self.is_primitive
        msg.is_array = self.is_array
        msg.array_size = self.array_size
        return msg


@dataclass(frozen=True)
class ContractDescriptor:
    """A catalogue entry as the atlas serves it: id, version, kind, mode, IDL types and fields."""
    id: str
    version: str = ""
    kind: Kind = Kind.UNSPECIFIED
    mode: str = ""
    io_msg_type: str = ""
    io_srv_type: str = ""
    source_toml_path: str = ""
    msg_fields: tuple[FieldSpec, ...] = ()
    srv_request_fields: tuple[FieldSpec, ...] = ()
    srv_response_fields: tuple[FieldSpec, ...] = ()
    description: str = ""
    cross_namespace: bool = False

    def __post_init__(self) -> None:
        # robonix-api's positional order puts ``description`` right after ``source_toml_path``.
        if isinstance(self.msg_fields, str):
            desc, msg, req, resp = (self.msg_fields, self.srv_request_fields, self.srv_response_fields,
                                    self.description)
            object.__setattr__(self, "description", desc)
            object.__setattr__(self, "msg_fields", tuple(msg))
            object.__setattr__(self, "srv_request_fields", tuple(req))
            object.__setattr__(self, "srv_response_fields", tuple(resp) if not isinstance(resp, str) else ())

    @classmethod
    def from_pb(cls, pb: atlas_pb2.ContractDescriptor) -> ContractDescriptor:
        """From the atlas's protobuf record."""
        return cls(
            id=pb.id,
            version=pb.version,
            kind=_enum_or_raw(Kind, pb.kind),
            mode=pb.mode,
            io_msg_type=pb.io_msg_type,
            io_srv_type=pb.io_srv_type,
            source_toml_path=pb.source_toml_path,
            msg_fields=tuple(FieldSpec.from_pb(f) for f in pb.msg_fields),
            srv_request_fields=tuple(FieldSpec.from_pb(f) for f in pb.srv_request_fields),
            srv_response_fields=tuple(FieldSpec.from_pb(f) for f in pb.srv_response_fields),
            description=pb.description,
            cross_namespace=pb.cross_namespace,
        )

    def to_pb(self, out: atlas_pb2.ContractDescriptor | None = None) -> atlas_pb2.ContractDescriptor:
        """As the atlas's protobuf record (into ``out`` when given)."""
        msg = out if out is not None else atlas_pb2.ContractDescriptor()
        msg.id = self.id
        msg.version = self.version
        msg.kind = int(self.kind)
        msg.mode = self.mode
        msg.io_msg_type = self.io_msg_type
        msg.io_srv_type = self.io_srv_type
        msg.source_toml_path = self.source_toml_path
        for f in self.msg_fields:
            f.to_pb(msg.msg_fields.add())
        for f in self.srv_request_fields:
            f.to_pb(msg.srv_request_fields.add())
        for f in self.srv_response_fields:
            f.to_pb(msg.srv_response_fields.add())
        msg.description = self.description
        msg.cross_namespace = self.cross_namespace
        return msg


__all__ = [
    "Capability",
    "CapabilityProvider",
    "Channel",
    "ContractDescriptor",
    "FieldSpec",
    "GrpcParams",
    "Kind",
    "LifecycleState",
    "McpParams",
    "Ros2Params",
    "Transport",
    "TransportParams",
    "default_params",
    "params_from_pb",
    "params_to_dict",
    "params_to_pb",
]
