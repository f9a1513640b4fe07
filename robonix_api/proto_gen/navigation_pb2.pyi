from . import geometry_msgs_pb2 as _geometry_msgs_pb2
from google.protobuf import descriptor as _descriptor
from google.protobuf import message as _message
from collections.abc import Mapping as _Mapping
from typing import ClassVar as _ClassVar, Optional as _Optional, Union as _Union

DESCRIPTOR: _descriptor.FileDescriptor

class NavigationStatus(_message.Message):
    __slots__ = ("goal_id", "status")
    GOAL_ID_FIELD_NUMBER: _ClassVar[int]
    STATUS_FIELD_NUMBER: _ClassVar[int]
    goal_id: str
    status: str
    def __init__(self, goal_id: _Optional[str] = ..., status: _Optional[str] = ...) -> None: ...

class Navigate_Request(_message.Message):
    __slots__ = ("goal",)
    GOAL_FIELD_NUMBER: _ClassVar[int]
    goal: _geometry_msgs_pb2.PoseStamped
    def __init__(self, goal: _Optional[_Union[_geometry_msgs_pb2.PoseStamped, _Mapping]] = ...) -> None: ...

class Navigate_Response(_message.Message):
    __slots__ = ("accepted", "run_id", "detail")
    ACCEPTED_FIELD_NUMBER: _ClassVar[int]
    RUN_ID_FIELD_NUMBER: _ClassVar[int]
    DETAIL_FIELD_NUMBER: _ClassVar[int]
    accepted: bool
    run_id: str
    detail: str
    def __init__(self, accepted: _Optional[bool] = ..., run_id: _Optional[str] = ..., detail: _Optional[str] = ...) -> None: ...

class GetNavigationStatus_Request(_message.Message):
    __slots__ = ("run_id",)
    RUN_ID_FIELD_NUMBER: _ClassVar[int]
    run_id: str
    def __init__(self, run_id: _Optional[str] = ...) -> None: ...

class GetNavigationStatus_Response(_message.Message):
    __slots__ = ("known", "state", "detail")
    KNOWN_FIELD_NUMBER: _ClassVar[int]
    STATE_FIELD_NUMBER: _ClassVar[int]
    DETAIL_FIELD_NUMBER: _ClassVar[int]
    known: bool
    state: str
    detail: str
    def __init__(self, known: _Optional[bool] = ..., state: _Optional[str] = ..., detail: _Optional[str] = ...) -> None: ...

class CancelNavigation_Request(_message.Message):
    __slots__ = ("run_id",)
    RUN_ID_FIELD_NUMBER: _ClassVar[int]
    run_id: str
    def __init__(self, run_id: _Optional[str] = ...) -> None: ...

class CancelNavigation_Response(_message.Message):
    __slots__ = ("accepted", "detail")
    ACCEPTED_FIELD_NUMBER: _ClassVar[int]
    DETAIL_FIELD_NUMBER: _ClassVar[int]
    accepted: bool
    detail: str
    def __init__(self, accepted: _Optional[bool] = ..., detail: _Optional[str] = ...) -> None: ...

class AdjustNavigationSpeed_Request(_message.Message):
    __slots__ = ("direction", "run_id", "persist")
    DIRECTION_FIELD_NUMBER: _ClassVar[int]
    RUN_ID_FIELD_NUMBER: _ClassVar[int]
    PERSIST_FIELD_NUMBER: _ClassVar[int]
    direction: str
    run_id: str
    persist: bool
    def __init__(self, direction: _Optional[str] = ..., run_id: _Optional[str] = ..., persist: _Optional[bool] = ...) -> None: ...

class AdjustNavigationSpeed_Response(_message.Message):
    __slots__ = ("accepted", "changed", "effective_percentage", "effective_linear_speed_mps", "scope", "run_id", "detail")
    ACCEPTED_FIELD_NUMBER: _ClassVar[int]
    CHANGED_FIELD_NUMBER: _ClassVar[int]
    EFFECTIVE_PERCENTAGE_FIELD_NUMBER: _ClassVar[int]
    EFFECTIVE_LINEAR_SPEED_MPS_FIELD_NUMBER: _ClassVar[int]
    SCOPE_FIELD_NUMBER: _ClassVar[int]
    RUN_ID_FIELD_NUMBER: _ClassVar[int]
    DETAIL_FIELD_NUMBER: _ClassVar[int]
    accepted: bool
    changed: bool
    effective_percentage: float
    effective_linear_speed_mps: float
    scope: str
    run_id: str
    detail: str
    def __init__(self, accepted: _Optional[bool] = ..., changed: _Optional[bool] = ..., effective_percentage: _Optional[float] = ..., effective_linear_speed_mps: _Optional[float] = ..., scope: _Optional[str] = ..., run_id: _Optional[str] = ..., detail: _Optional[str] = ...) -> None: ...

class SetNavigationSpeedLimit_Request(_message.Message):
    __slots__ = ("percentage", "run_id", "persist")
    PERCENTAGE_FIELD_NUMBER: _ClassVar[int]
    RUN_ID_FIELD_NUMBER: _ClassVar[int]
    PERSIST_FIELD_NUMBER: _ClassVar[int]
    percentage: float
    run_id: str
    persist: bool
    def __init__(self, percentage: _Optional[float] = ..., run_id: _Optional[str] = ..., persist: _Optional[bool] = ...) -> None: ...

class SetNavigationSpeedLimit_Response(_message.Message):
    __slots__ = ("accepted", "changed", "effective_percentage", "effective_linear_speed_mps", "scope", "run_id", "detail")
    ACCEPTED_FIELD_NUMBER: _ClassVar[int]
    CHANGED_FIELD_NUMBER: _ClassVar[int]
    EFFECTIVE_PERCENTAGE_FIELD_NUMBER: _ClassVar[int]
    EFFECTIVE_LINEAR_SPEED_MPS_FIELD_NUMBER: _ClassVar[int]
    SCOPE_FIELD_NUMBER: _ClassVar[int]
    RUN_ID_FIELD_NUMBER: _ClassVar[int]
    DETAIL_FIELD_NUMBER: _ClassVar[int]
    accepted: bool
    changed: bool
    effective_percentage: float
    effective_linear_speed_mps: float
    scope: str
    run_id: str
    detail: str
    def __init__(self, accepted: _Optional[bool] = ..., changed: _Optional[bool] = ..., effective_percentage: _Optional[float] = ..., effective_linear_speed_mps: _Optional[float] = ..., scope: _Optional[str] = ..., run_id: _Optional[str] = ..., detail: _Optional[str] = ...) -> None: ...

class GetNavigationSpeedLimit_Request(_message.Message):
    __slots__ = ()
    def __init__(self) -> None: ...

class GetNavigationSpeedLimit_Response(_message.Message):
    __slots__ = ("available", "max_linear_speed_mps", "default_percentage", "min_percentage", "step_percentage", "effective_percentage", "effective_linear_speed_mps", "scope", "run_id", "detail")
    AVAILABLE_FIELD_NUMBER: _ClassVar[int]
    MAX_LINEAR_SPEED_MPS_FIELD_NUMBER: _ClassVar[int]
    DEFAULT_PERCENTAGE_FIELD_NUMBER: _ClassVar[int]
    MIN_PERCENTAGE_FIELD_NUMBER: _ClassVar[int]
    STEP_PERCENTAGE_FIELD_NUMBER: _ClassVar[int]
    EFFECTIVE_PERCENTAGE_FIELD_NUMBER: _ClassVar[int]
    EFFECTIVE_LINEAR_SPEED_MPS_FIELD_NUMBER: _ClassVar[int]
    SCOPE_FIELD_NUMBER: _ClassVar[int]
    RUN_ID_FIELD_NUMBER: _ClassVar[int]
    DETAIL_FIELD_NUMBER: _ClassVar[int]
    available: bool
    max_linear_speed_mps: float
    default_percentage: float
    min_percentage: float
    step_percentage: float
    effective_percentage: float
    effective_linear_speed_mps: float
    scope: str
    run_id: str
    detail: str
    def __init__(self, available: _Optional[bool] = ..., max_linear_speed_mps: _Optional[float] = ..., default_percentage: _Optional[float] = ..., min_percentage: _Optional[float] = ..., step_percentage: _Optional[float] = ..., effective_percentage: _Optional[float] = ..., effective_linear_speed_mps: _Optional[float] = ..., scope: _Optional[str] = ..., run_id: _Optional[str] = ..., detail: _Optional[str] = ...) -> None: ...
