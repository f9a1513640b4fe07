from google.protobuf.internal import containers as _containers
from google.protobuf.internal import enum_type_wrapper as _enum_type_wrapper
from google.protobuf import descriptor as _descriptor
from google.protobuf import message as _message
from collections.abc import Iterable as _Iterable, Mapping as _Mapping
from typing import ClassVar as _ClassVar, Optional as _Optional, Union as _Union

DESCRIPTOR: _descriptor.FileDescriptor

class Transport(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = ()
    TRANSPORT_UNSPECIFIED: _ClassVar[Transport]
    TRANSPORT_GRPC: _ClassVar[Transport]
    TRANSPORT_ROS2: _ClassVar[Transport]
    TRANSPORT_MCP: _ClassVar[Transport]

class Kind(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = ()
    KIND_UNSPECIFIED: _ClassVar[Kind]
    KIND_PRIMITIVE: _ClassVar[Kind]
    KIND_SERVICE: _ClassVar[Kind]
    KIND_SKILL: _ClassVar[Kind]

class LifecycleState(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = ()
    STATE_UNSPECIFIED: _ClassVar[LifecycleState]
    STATE_REGISTERED: _ClassVar[LifecycleState]
    STATE_INACTIVE: _ClassVar[LifecycleState]
    STATE_ACTIVE: _ClassVar[LifecycleState]
    STATE_ERROR: _ClassVar[LifecycleState]
    STATE_TERMINATED: _ClassVar[LifecycleState]
TRANSPORT_UNSPECIFIED: Transport
TRANSPORT_GRPC: Transport
TRANSPORT_ROS2: Transport
TRANSPORT_MCP: Transport
KIND_UNSPECIFIED: Kind
KIND_PRIMITIVE: Kind
KIND_SERVICE: Kind
KIND_SKILL: Kind
STATE_UNSPECIFIED: LifecycleState
STATE_REGISTERED: LifecycleState
STATE_INACTIVE: LifecycleState
STATE_ACTIVE: LifecycleState
STATE_ERROR: LifecycleState
STATE_TERMINATED: LifecycleState

class RegisterRequest(_message.Message):
    __slots__ = ("id", "namespace", "capability_md_path", "capability_md")
    ID_FIELD_NUMBER: _ClassVar[int]
    NAMESPACE_FIELD_NUMBER: _ClassVar[int]
    CAPABILITY_MD_PATH_FIELD_NUMBER: _ClassVar[int]
    CAPABILITY_MD_FIELD_NUMBER: _ClassVar[int]
    id: str
    namespace: str
    capability_md_path: str
    capability_md: str
    def __init__(self, id: _Optional[str] = ..., namespace: _Optional[str] = ..., capability_md_path: _Optional[str] = ..., capability_md: _Optional[str] = ...) -> None: ...

class RegisterResponse(_message.Message):
    __slots__ = ("id",)
    ID_FIELD_NUMBER: _ClassVar[int]
    id: str
    def __init__(self, id: _Optional[str] = ...) -> None: ...

class UnregisterRequest(_message.Message):
    __slots__ = ("id",)
    ID_FIELD_NUMBER: _ClassVar[int]
    id: str
    def __init__(self, id: _Optional[str] = ...) -> None: ...

class UnregisterResponse(_message.Message):
    __slots__ = ("was_present",)
    WAS_PRESENT_FIELD_NUMBER: _ClassVar[int]
    was_present: bool
    def __init__(self, was_present: _Optional[bool] = ...) -> None: ...

class HeartbeatRequest(_message.Message):
    __slots__ = ("id",)
    ID_FIELD_NUMBER: _ClassVar[int]
    id: str
    def __init__(self, id: _Optional[str] = ...) -> None: ...

class HeartbeatResponse(_message.Message):
    __slots__ = ()
    def __init__(self) -> None: ...

class GrpcParams(_message.Message):
    __slots__ = ("proto_file", "service_name", "method")
    PROTO_FILE_FIELD_NUMBER: _ClassVar[int]
    SERVICE_NAME_FIELD_NUMBER: _ClassVar[int]
    METHOD_FIELD_NUMBER: _ClassVar[int]
    proto_file: str
    service_name: str
    method: str
    def __init__(self, proto_file: _Optional[str] = ..., service_name: _Optional[str] = ..., method: _Optional[str] = ...) -> None: ...

class Ros2Params(_message.Message):
    __slots__ = ("qos_profile",)
    QOS_PROFILE_FIELD_NUMBER: _ClassVar[int]
    qos_profile: str
    def __init__(self, qos_profile: _Optional[str] = ...) -> None: ...

class McpParams(_message.Message):
    __slots__ = ("input_schema_json",)
    INPUT_SCHEMA_JSON_FIELD_NUMBER: _ClassVar[int]
    input_schema_json: str
    def __init__(self, input_schema_json: _Optional[str] = ...) -> None: ...

class TransportParams(_message.Message):
    __slots__ = ("grpc", "ros2", "mcp")
    GRPC_FIELD_NUMBER: _ClassVar[int]
    ROS2_FIELD_NUMBER: _ClassVar[int]
    MCP_FIELD_NUMBER: _ClassVar[int]
    grpc: GrpcParams
    ros2: Ros2Params
    mcp: McpParams
    def __init__(self, grpc: _Optional[_Union[GrpcParams, _Mapping]] = ..., ros2: _Optional[_Union[Ros2Params, _Mapping]] = ..., mcp: _Optional[_Union[McpParams, _Mapping]] = ...) -> None: ...

class DeclareCapabilityRequest(_message.Message):
    __slots__ = ("provider_id", "contract_id", "transport", "endpoint", "params", "description")
    PROVIDER_ID_FIELD_NUMBER: _ClassVar[int]
    CONTRACT_ID_FIELD_NUMBER: _ClassVar[int]
    TRANSPORT_FIELD_NUMBER: _ClassVar[int]
    ENDPOINT_FIELD_NUMBER: _ClassVar[int]
    PARAMS_FIELD_NUMBER: _ClassVar[int]
    DESCRIPTION_FIELD_NUMBER: _ClassVar[int]
    provider_id: str
    contract_id: str
    transport: Transport
    endpoint: str
    params: TransportParams
    description: str
    def __init__(self, provider_id: _Optional[str] = ..., contract_id: _Optional[str] = ..., transport: _Optional[_Union[Transport, str]] = ..., endpoint: _Optional[str] = ..., params: _Optional[_Union[TransportParams, _Mapping]] = ..., description: _Optional[str] = ...) -> None: ...

class DeclareCapabilityResponse(_message.Message):
    __slots__ = ("endpoint",)
    ENDPOINT_FIELD_NUMBER: _ClassVar[int]
    endpoint: str
    def __init__(self, endpoint: _Optional[str] = ...) -> None: ...

class Capability(_message.Message):
    __slots__ = ("provider_id", "provider_kind", "contract_id", "transport", "params", "description", "namespace_mismatch")
    PROVIDER_ID_FIELD_NUMBER: _ClassVar[int]
    PROVIDER_KIND_FIELD_NUMBER: _ClassVar[int]
    CONTRACT_ID_FIELD_NUMBER: _ClassVar[int]
    TRANSPORT_FIELD_NUMBER: _ClassVar[int]
    PARAMS_FIELD_NUMBER: _ClassVar[int]
    DESCRIPTION_FIELD_NUMBER: _ClassVar[int]
    NAMESPACE_MISMATCH_FIELD_NUMBER: _ClassVar[int]
    provider_id: str
    provider_kind: Kind
    contract_id: str
    transport: Transport
    params: TransportParams
    description: str
    namespace_mismatch: bool
    def __init__(self, provider_id: _Optional[str] = ..., provider_kind: _Optional[_Union[Kind, str]] = ..., contract_id: _Optional[str] = ..., transport: _Optional[_Union[Transport, str]] = ..., params: _Optional[_Union[TransportParams, _Mapping]] = ..., description: _Optional[str] = ..., namespace_mismatch: _Optional[bool] = ...) -> None: ...

class SetLifecycleStateRequest(_message.Message):
    __slots__ = ("id", "state", "detail")
    ID_FIELD_NUMBER: _ClassVar[int]
    STATE_FIELD_NUMBER: _ClassVar[int]
    DETAIL_FIELD_NUMBER: _ClassVar[int]
    id: str
    state: LifecycleState
    detail: str
    def __init__(self, id: _Optional[str] = ..., state: _Optional[_Union[LifecycleState, str]] = ..., detail: _Optional[str] = ...) -> None: ...

class SetLifecycleStateResponse(_message.Message):
    __slots__ = ("previous_state",)
    PREVIOUS_STATE_FIELD_NUMBER: _ClassVar[int]
    previous_state: LifecycleState
    def __init__(self, previous_state: _Optional[_Union[LifecycleState, str]] = ...) -> None: ...

class CapabilityProvider(_message.Message):
    __slots__ = ("id", "kind", "namespace", "capability_md_path", "last_heartbeat_ms", "state", "state_detail", "capabilities", "capability_md", "registration_id")
    ID_FIELD_NUMBER: _ClassVar[int]
    KIND_FIELD_NUMBER: _ClassVar[int]
    NAMESPACE_FIELD_NUMBER: _ClassVar[int]
    CAPABILITY_MD_PATH_FIELD_NUMBER: _ClassVar[int]
    LAST_HEARTBEAT_MS_FIELD_NUMBER: _ClassVar[int]
    STATE_FIELD_NUMBER: _ClassVar[int]
    STATE_DETAIL_FIELD_NUMBER: _ClassVar[int]
    CAPABILITIES_FIELD_NUMBER: _ClassVar[int]
    CAPABILITY_MD_FIELD_NUMBER: _ClassVar[int]
    REGISTRATION_ID_FIELD_NUMBER: _ClassVar[int]
    id: str
    kind: Kind
    namespace: str
    capability_md_path: str
    last_heartbeat_ms: int
    state: LifecycleState
    state_detail: str
    capabilities: _containers.RepeatedCompositeFieldContainer[Capability]
    capability_md: str
    registration_id: str
    def __init__(self, id: _Optional[str] = ..., kind: _Optional[_Union[Kind, str]] = ..., namespace: _Optional[str] = ..., capability_md_path: _Optional[str] = ..., last_heartbeat_ms: _Optional[int] = ..., state: _Optional[_Union[LifecycleState, str]] = ..., state_detail: _Optional[str] = ..., capabilities: _Optional[_Iterable[_Union[Capability, _Mapping]]] = ..., capability_md: _Optional[str] = ..., registration_id: _Optional[str] = ...) -> None: ...

class QueryRequest(_message.Message):
    __slots__ = ("kind", "id", "contract_id", "transport", "namespace_prefix")
    KIND_FIELD_NUMBER: _ClassVar[int]
    ID_FIELD_NUMBER: _ClassVar[int]
    CONTRACT_ID_FIELD_NUMBER: _ClassVar[int]
    TRANSPORT_FIELD_NUMBER: _ClassVar[int]
    NAMESPACE_PREFIX_FIELD_NUMBER: _ClassVar[int]
    kind: Kind
    id: str
    contract_id: str
    transport: Transport
    namespace_prefix: str
    def __init__(self, kind: _Optional[_Union[Kind, str]] = ..., id: _Optional[str] = ..., contract_id: _Optional[str] = ..., transport: _Optional[_Union[Transport, str]] = ..., namespace_prefix: _Optional[str] = ...) -> None: ...

class QueryResponse(_message.Message):
    __slots__ = ("providers",)
    PROVIDERS_FIELD_NUMBER: _ClassVar[int]
    providers: _containers.RepeatedCompositeFieldContainer[CapabilityProvider]
    def __init__(self, providers: _Optional[_Iterable[_Union[CapabilityProvider, _Mapping]]] = ...) -> None: ...

class ConnectCapabilityRequest(_message.Message):
    __slots__ = ("consumer_id", "provider_id", "contract_id", "transport")
    CONSUMER_ID_FIELD_NUMBER: _ClassVar[int]
    PROVIDER_ID_FIELD_NUMBER: _ClassVar[int]
    CONTRACT_ID_FIELD_NUMBER: _ClassVar[int]
    TRANSPORT_FIELD_NUMBER: _ClassVar[int]
    consumer_id: str
    provider_id: str
    contract_id: str
    transport: Transport
    def __init__(self, consumer_id: _Optional[str] = ..., provider_id: _Optional[str] = ..., contract_id: _Optional[str] = ..., transport: _Optional[_Union[Transport, str]] = ...) -> None: ...

class ConnectCapabilityResponse(_message.Message):
    __slots__ = ("channel_id", "endpoint", "params")
    CHANNEL_ID_FIELD_NUMBER: _ClassVar[int]
    ENDPOINT_FIELD_NUMBER: _ClassVar[int]
    PARAMS_FIELD_NUMBER: _ClassVar[int]
    channel_id: str
    endpoint: str
    params: TransportParams
    def __init__(self, channel_id: _Optional[str] = ..., endpoint: _Optional[str] = ..., params: _Optional[_Union[TransportParams, _Mapping]] = ...) -> None: ...

class DisconnectCapabilityRequest(_message.Message):
    __slots__ = ("channel_id",)
    CHANNEL_ID_FIELD_NUMBER: _ClassVar[int]
    channel_id: str
    def __init__(self, channel_id: _Optional[str] = ...) -> None: ...

class DisconnectCapabilityResponse(_message.Message):
    __slots__ = ("was_open",)
    WAS_OPEN_FIELD_NUMBER: _ClassVar[int]
    was_open: bool
    def __init__(self, was_open: _Optional[bool] = ...) -> None: ...

class FieldSpec(_message.Message):
    __slots__ = ("name", "type_name", "is_primitive", "is_array", "array_size")
    NAME_FIELD_NUMBER: _ClassVar[int]
    TYPE_NAME_FIELD_NUMBER: _ClassVar[int]
    IS_PRIMITIVE_FIELD_NUMBER: _ClassVar[int]
    IS_ARRAY_FIELD_NUMBER: _ClassVar[int]
    ARRAY_SIZE_FIELD_NUMBER: _ClassVar[int]
    name: str
    type_name: str
    is_primitive: bool
    is_array: bool
    array_size: int
    def __init__(self, name: _Optional[str] = ..., type_name: _Optional[str] = ..., is_primitive: _Optional[bool] = ..., is_array: _Optional[bool] = ..., array_size: _Optional[int] = ...) -> None: ...

class ContractDescriptor(_message.Message):
    __slots__ = ("id", "version", "kind", "mode", "io_msg_type", "io_srv_type", "source_toml_path", "msg_fields", "srv_request_fields", "srv_response_fields", "description", "cross_namespace")
    ID_FIELD_NUMBER: _ClassVar[int]
    VERSION_FIELD_NUMBER: _ClassVar[int]
    KIND_FIELD_NUMBER: _ClassVar[int]
    MODE_FIELD_NUMBER: _ClassVar[int]
    IO_MSG_TYPE_FIELD_NUMBER: _ClassVar[int]
    IO_SRV_TYPE_FIELD_NUMBER: _ClassVar[int]
    SOURCE_TOML_PATH_FIELD_NUMBER: _ClassVar[int]
    MSG_FIELDS_FIELD_NUMBER: _ClassVar[int]
    SRV_REQUEST_FIELDS_FIELD_NUMBER: _ClassVar[int]
    SRV_RESPONSE_FIELDS_FIELD_NUMBER: _ClassVar[int]
    DESCRIPTION_FIELD_NUMBER: _ClassVar[int]
    CROSS_NAMESPACE_FIELD_NUMBER: _ClassVar[int]
    id: str
    version: str
    kind: Kind
    mode: str
    io_msg_type: str
    io_srv_type: str
    source_toml_path: str
    msg_fields: _containers.RepeatedCompositeFieldContainer[FieldSpec]
    srv_request_fields: _containers.RepeatedCompositeFieldContainer[FieldSpec]
    srv_response_fields: _containers.RepeatedCompositeFieldContainer[FieldSpec]
    description: str
    cross_namespace: bool
    def __init__(self, id: _Optional[str] = ..., version: _Optional[str] = ..., kind: _Optional[_Union[Kind, str]] = ..., mode: _Optional[str] = ..., io_msg_type: _Optional[str] = ..., io_srv_type: _Optional[str] = ..., source_toml_path: _Optional[str] = ..., msg_fields: _Optional[_Iterable[_Union[FieldSpec, _Mapping]]] = ..., srv_request_fields: _Optional[_Iterable[_Union[FieldSpec, _Mapping]]] = ..., srv_response_fields: _Optional[_Iterable[_Union[FieldSpec, _Mapping]]] = ..., description: _Optional[str] = ..., cross_namespace: _Optional[bool] = ...) -> None: ...

class QueryContractRequest(_message.Message):
    __slots__ = ("contract_id",)
    CONTRACT_ID_FIELD_NUMBER: _ClassVar[int]
    contract_id: str
    def __init__(self, contract_id: _Optional[str] = ...) -> None: ...

class QueryContractResponse(_message.Message):
    __slots__ = ("contract", "found")
    CONTRACT_FIELD_NUMBER: _ClassVar[int]
    FOUND_FIELD_NUMBER: _ClassVar[int]
    contract: ContractDescriptor
    found: bool
    def __init__(self, contract: _Optional[_Union[ContractDescriptor, _Mapping]] = ..., found: _Optional[bool] = ...) -> None: ...

class ListContractsRequest(_message.Message):
    __slots__ = ("namespace_prefix",)
    NAMESPACE_PREFIX_FIELD_NUMBER: _ClassVar[int]
    namespace_prefix: str
    def __init__(self, namespace_prefix: _Optional[str] = ...) -> None: ...

class ListContractsResponse(_message.Message):
    __slots__ = ("contracts",)
    CONTRACTS_FIELD_NUMBER: _ClassVar[int]
    contracts: _containers.RepeatedCompositeFieldContainer[ContractDescriptor]
    def __init__(self, contracts: _Optional[_Iterable[_Union[ContractDescriptor, _Mapping]]] = ...) -> None: ...

class InspectAtlasRequest(_message.Message):
    __slots__ = ()
    def __init__(self) -> None: ...

class InspectAtlasResponse(_message.Message):
    __slots__ = ("json",)
    JSON_FIELD_NUMBER: _ClassVar[int]
    json: str
    def __init__(self, json: _Optional[str] = ...) -> None: ...
