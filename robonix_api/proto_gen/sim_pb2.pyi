from . import builtin_interfaces_pb2 as _builtin_interfaces_pb2
from google.protobuf.internal import containers as _containers
from google.protobuf import descriptor as _descriptor
from google.protobuf import message as _message
from collections.abc import Iterable as _Iterable, Mapping as _Mapping
from typing import ClassVar as _ClassVar, Optional as _Optional, Union as _Union

DESCRIPTOR: _descriptor.FileDescriptor

class CollisionEvent(_message.Message):
    __slots__ = ("stamp", "robot_geom", "other_geom", "x", "y")
    STAMP_FIELD_NUMBER: _ClassVar[int]
    ROBOT_GEOM_FIELD_NUMBER: _ClassVar[int]
    OTHER_GEOM_FIELD_NUMBER: _ClassVar[int]
    X_FIELD_NUMBER: _ClassVar[int]
    Y_FIELD_NUMBER: _ClassVar[int]
    stamp: _builtin_interfaces_pb2.Time
    robot_geom: str
    other_geom: str
    x: float
    y: float
    def __init__(self, stamp: _Optional[_Union[_builtin_interfaces_pb2.Time, _Mapping]] = ..., robot_geom: _Optional[str] = ..., other_geom: _Optional[str] = ..., x: _Optional[float] = ..., y: _Optional[float] = ...) -> None: ...

class GetGroundTruth_Request(_message.Message):
    __slots__ = ()
    def __init__(self) -> None: ...

class GetGroundTruth_Response(_message.Message):
    __slots__ = ("ok", "x", "y", "theta", "vx", "vy", "wz", "sim_time", "detail")
    OK_FIELD_NUMBER: _ClassVar[int]
    X_FIELD_NUMBER: _ClassVar[int]
    Y_FIELD_NUMBER: _ClassVar[int]
    THETA_FIELD_NUMBER: _ClassVar[int]
    VX_FIELD_NUMBER: _ClassVar[int]
    VY_FIELD_NUMBER: _ClassVar[int]
    WZ_FIELD_NUMBER: _ClassVar[int]
    SIM_TIME_FIELD_NUMBER: _ClassVar[int]
    DETAIL_FIELD_NUMBER: _ClassVar[int]
    ok: bool
    x: float
    y: float
    theta: float
    vx: float
    vy: float
    wz: float
    sim_time: float
    detail: str
    def __init__(self, ok: _Optional[bool] = ..., x: _Optional[float] = ..., y: _Optional[float] = ..., theta: _Optional[float] = ..., vx: _Optional[float] = ..., vy: _Optional[float] = ..., wz: _Optional[float] = ..., sim_time: _Optional[float] = ..., detail: _Optional[str] = ...) -> None: ...

class GetCollisions_Request(_message.Message):
    __slots__ = ("since_sim_time",)
    SINCE_SIM_TIME_FIELD_NUMBER: _ClassVar[int]
    since_sim_time: float
    def __init__(self, since_sim_time: _Optional[float] = ...) -> None: ...

class GetCollisions_Response(_message.Message):
    __slots__ = ("ok", "count", "events", "detail")
    OK_FIELD_NUMBER: _ClassVar[int]
    COUNT_FIELD_NUMBER: _ClassVar[int]
    EVENTS_FIELD_NUMBER: _ClassVar[int]
    DETAIL_FIELD_NUMBER: _ClassVar[int]
    ok: bool
    count: int
    events: _containers.RepeatedCompositeFieldContainer[CollisionEvent]
    detail: str
    def __init__(self, ok: _Optional[bool] = ..., count: _Optional[int] = ..., events: _Optional[_Iterable[_Union[CollisionEvent, _Mapping]]] = ..., detail: _Optional[str] = ...) -> None: ...

class Teleport_Request(_message.Message):
    __slots__ = ("x", "y", "theta")
    X_FIELD_NUMBER: _ClassVar[int]
    Y_FIELD_NUMBER: _ClassVar[int]
    THETA_FIELD_NUMBER: _ClassVar[int]
    x: float
    y: float
    theta: float
    def __init__(self, x: _Optional[float] = ..., y: _Optional[float] = ..., theta: _Optional[float] = ...) -> None: ...

class Teleport_Response(_message.Message):
    __slots__ = ("ok", "detail")
    OK_FIELD_NUMBER: _ClassVar[int]
    DETAIL_FIELD_NUMBER: _ClassVar[int]
    ok: bool
    detail: str
    def __init__(self, ok: _Optional[bool] = ..., detail: _Optional[str] = ...) -> None: ...

class ResetSim_Request(_message.Message):
    __slots__ = ()
    def __init__(self) -> None: ...

class ResetSim_Response(_message.Message):
    __slots__ = ("ok", "detail")
    OK_FIELD_NUMBER: _ClassVar[int]
    DETAIL_FIELD_NUMBER: _ClassVar[int]
    ok: bool
    detail: str
    def __init__(self, ok: _Optional[bool] = ..., detail: _Optional[str] = ...) -> None: ...

class GetSceneInfo_Request(_message.Message):
    __slots__ = ()
    def __init__(self) -> None: ...

class GetSceneInfo_Response(_message.Message):
    __slots__ = ("ok", "scene", "info_json", "detail")
    OK_FIELD_NUMBER: _ClassVar[int]
    SCENE_FIELD_NUMBER: _ClassVar[int]
    INFO_JSON_FIELD_NUMBER: _ClassVar[int]
    DETAIL_FIELD_NUMBER: _ClassVar[int]
    ok: bool
    scene: str
    info_json: str
    detail: str
    def __init__(self, ok: _Optional[bool] = ..., scene: _Optional[str] = ..., info_json: _Optional[str] = ..., detail: _Optional[str] = ...) -> None: ...

class SpawnObstacle_Request(_message.Message):
    __slots__ = ("name", "x", "y", "size_x", "size_y", "yaw")
    NAME_FIELD_NUMBER: _ClassVar[int]
    X_FIELD_NUMBER: _ClassVar[int]
    Y_FIELD_NUMBER: _ClassVar[int]
    SIZE_X_FIELD_NUMBER: _ClassVar[int]
    SIZE_Y_FIELD_NUMBER: _ClassVar[int]
    YAW_FIELD_NUMBER: _ClassVar[int]
    name: str
    x: float
    y: float
    size_x: float
    size_y: float
    yaw: float
    def __init__(self, name: _Optional[str] = ..., x: _Optional[float] = ..., y: _Optional[float] = ..., size_x: _Optional[float] = ..., size_y: _Optional[float] = ..., yaw: _Optional[float] = ...) -> None: ...

class SpawnObstacle_Response(_message.Message):
    __slots__ = ("ok", "detail")
    OK_FIELD_NUMBER: _ClassVar[int]
    DETAIL_FIELD_NUMBER: _ClassVar[int]
    ok: bool
    detail: str
    def __init__(self, ok: _Optional[bool] = ..., detail: _Optional[str] = ...) -> None: ...
