from google.protobuf.internal import containers as _containers
from google.protobuf import descriptor as _descriptor
from google.protobuf import message as _message
from collections.abc import Iterable as _Iterable
from typing import ClassVar as _ClassVar, Optional as _Optional

DESCRIPTOR: _descriptor.FileDescriptor

class MapLifecycle(_message.Message):
    __slots__ = ("map_id", "mode", "generation")
    MAP_ID_FIELD_NUMBER: _ClassVar[int]
    MODE_FIELD_NUMBER: _ClassVar[int]
    GENERATION_FIELD_NUMBER: _ClassVar[int]
    map_id: str
    mode: str
    generation: int
    def __init__(self, map_id: _Optional[str] = ..., mode: _Optional[str] = ..., generation: _Optional[int] = ...) -> None: ...

class SaveMap_Request(_message.Message):
    __slots__ = ("map_id", "note")
    MAP_ID_FIELD_NUMBER: _ClassVar[int]
    NOTE_FIELD_NUMBER: _ClassVar[int]
    map_id: str
    note: str
    def __init__(self, map_id: _Optional[str] = ..., note: _Optional[str] = ...) -> None: ...

class SaveMap_Response(_message.Message):
    __slots__ = ("ok", "map_id", "detail")
    OK_FIELD_NUMBER: _ClassVar[int]
    MAP_ID_FIELD_NUMBER: _ClassVar[int]
    DETAIL_FIELD_NUMBER: _ClassVar[int]
    ok: bool
    map_id: str
    detail: str
    def __init__(self, ok: _Optional[bool] = ..., map_id: _Optional[str] = ..., detail: _Optional[str] = ...) -> None: ...

class ListMaps_Request(_message.Message):
    __slots__ = ()
    def __init__(self) -> None: ...

class ListMaps_Response(_message.Message):
    __slots__ = ("ok", "detail", "maps_json")
    OK_FIELD_NUMBER: _ClassVar[int]
    DETAIL_FIELD_NUMBER: _ClassVar[int]
    MAPS_JSON_FIELD_NUMBER: _ClassVar[int]
    ok: bool
    detail: str
    maps_json: str
    def __init__(self, ok: _Optional[bool] = ..., detail: _Optional[str] = ..., maps_json: _Optional[str] = ...) -> None: ...

class LoadMap_Request(_message.Message):
    __slots__ = ("map_id", "mode", "has_initial_pose", "x", "y", "theta")
    MAP_ID_FIELD_NUMBER: _ClassVar[int]
    MODE_FIELD_NUMBER: _ClassVar[int]
    HAS_INITIAL_POSE_FIELD_NUMBER: _ClassVar[int]
    X_FIELD_NUMBER: _ClassVar[int]
    Y_FIELD_NUMBER: _ClassVar[int]
    THETA_FIELD_NUMBER: _ClassVar[int]
    map_id: str
    mode: str
    has_initial_pose: bool
    x: float
    y: float
    theta: float
    def __init__(self, map_id: _Optional[str] = ..., mode: _Optional[str] = ..., has_initial_pose: _Optional[bool] = ..., x: _Optional[float] = ..., y: _Optional[float] = ..., theta: _Optional[float] = ...) -> None: ...

class LoadMap_Response(_message.Message):
    __slots__ = ("ok", "detail")
    OK_FIELD_NUMBER: _ClassVar[int]
    DETAIL_FIELD_NUMBER: _ClassVar[int]
    ok: bool
    detail: str
    def __init__(self, ok: _Optional[bool] = ..., detail: _Optional[str] = ...) -> None: ...

class PoseEstimate_Request(_message.Message):
    __slots__ = ("x", "y", "theta", "cov_xy", "cov_theta")
    X_FIELD_NUMBER: _ClassVar[int]
    Y_FIELD_NUMBER: _ClassVar[int]
    THETA_FIELD_NUMBER: _ClassVar[int]
    COV_XY_FIELD_NUMBER: _ClassVar[int]
    COV_THETA_FIELD_NUMBER: _ClassVar[int]
    x: float
    y: float
    theta: float
    cov_xy: float
    cov_theta: float
    def __init__(self, x: _Optional[float] = ..., y: _Optional[float] = ..., theta: _Optional[float] = ..., cov_xy: _Optional[float] = ..., cov_theta: _Optional[float] = ...) -> None: ...

class PoseEstimate_Response(_message.Message):
    __slots__ = ("ok", "detail")
    OK_FIELD_NUMBER: _ClassVar[int]
    DETAIL_FIELD_NUMBER: _ClassVar[int]
    ok: bool
    detail: str
    def __init__(self, ok: _Optional[bool] = ..., detail: _Optional[str] = ...) -> None: ...

class SwitchMode_Request(_message.Message):
    __slots__ = ("mode",)
    MODE_FIELD_NUMBER: _ClassVar[int]
    mode: str
    def __init__(self, mode: _Optional[str] = ...) -> None: ...

class SwitchMode_Response(_message.Message):
    __slots__ = ("ok", "detail")
    OK_FIELD_NUMBER: _ClassVar[int]
    DETAIL_FIELD_NUMBER: _ClassVar[int]
    ok: bool
    detail: str
    def __init__(self, ok: _Optional[bool] = ..., detail: _Optional[str] = ...) -> None: ...

class GetMode_Request(_message.Message):
    __slots__ = ()
    def __init__(self) -> None: ...

class GetMode_Response(_message.Message):
    __slots__ = ("ok", "mode", "detail")
    OK_FIELD_NUMBER: _ClassVar[int]
    MODE_FIELD_NUMBER: _ClassVar[int]
    DETAIL_FIELD_NUMBER: _ClassVar[int]
    ok: bool
    mode: str
    detail: str
    def __init__(self, ok: _Optional[bool] = ..., mode: _Optional[str] = ..., detail: _Optional[str] = ...) -> None: ...

class GetPose_Request(_message.Message):
    __slots__ = ()
    def __init__(self) -> None: ...

class GetPose_Response(_message.Message):
    __slots__ = ("ok", "x", "y", "theta", "frame_id", "detail")
    OK_FIELD_NUMBER: _ClassVar[int]
    X_FIELD_NUMBER: _ClassVar[int]
    Y_FIELD_NUMBER: _ClassVar[int]
    THETA_FIELD_NUMBER: _ClassVar[int]
    FRAME_ID_FIELD_NUMBER: _ClassVar[int]
    DETAIL_FIELD_NUMBER: _ClassVar[int]
    ok: bool
    x: float
    y: float
    theta: float
    frame_id: str
    detail: str
    def __init__(self, ok: _Optional[bool] = ..., x: _Optional[float] = ..., y: _Optional[float] = ..., theta: _Optional[float] = ..., frame_id: _Optional[str] = ..., detail: _Optional[str] = ...) -> None: ...

class DeleteMap_Request(_message.Message):
    __slots__ = ("map_id",)
    MAP_ID_FIELD_NUMBER: _ClassVar[int]
    map_id: str
    def __init__(self, map_id: _Optional[str] = ...) -> None: ...

class DeleteMap_Response(_message.Message):
    __slots__ = ("ok", "map_id", "detail")
    OK_FIELD_NUMBER: _ClassVar[int]
    MAP_ID_FIELD_NUMBER: _ClassVar[int]
    DETAIL_FIELD_NUMBER: _ClassVar[int]
    ok: bool
    map_id: str
    detail: str
    def __init__(self, ok: _Optional[bool] = ..., map_id: _Optional[str] = ..., detail: _Optional[str] = ...) -> None: ...

class ResetMap_Request(_message.Message):
    __slots__ = ()
    def __init__(self) -> None: ...

class ResetMap_Response(_message.Message):
    __slots__ = ("ok", "detail")
    OK_FIELD_NUMBER: _ClassVar[int]
    DETAIL_FIELD_NUMBER: _ClassVar[int]
    ok: bool
    detail: str
    def __init__(self, ok: _Optional[bool] = ..., detail: _Optional[str] = ...) -> None: ...

class GetMapCard_Request(_message.Message):
    __slots__ = ()
    def __init__(self) -> None: ...

class GetMapCard_Response(_message.Message):
    __slots__ = ("ok", "detail", "png", "width", "height", "resolution", "origin_x", "origin_y", "frame_id", "has_robot_pose", "robot_x", "robot_y", "robot_yaw", "footprint_polygon_xy")
    OK_FIELD_NUMBER: _ClassVar[int]
    DETAIL_FIELD_NUMBER: _ClassVar[int]
    PNG_FIELD_NUMBER: _ClassVar[int]
    WIDTH_FIELD_NUMBER: _ClassVar[int]
    HEIGHT_FIELD_NUMBER: _ClassVar[int]
    RESOLUTION_FIELD_NUMBER: _ClassVar[int]
    ORIGIN_X_FIELD_NUMBER: _ClassVar[int]
    ORIGIN_Y_FIELD_NUMBER: _ClassVar[int]
    FRAME_ID_FIELD_NUMBER: _ClassVar[int]
    HAS_ROBOT_POSE_FIELD_NUMBER: _ClassVar[int]
    ROBOT_X_FIELD_NUMBER: _ClassVar[int]
    ROBOT_Y_FIELD_NUMBER: _ClassVar[int]
    ROBOT_YAW_FIELD_NUMBER: _ClassVar[int]
    FOOTPRINT_POLYGON_XY_FIELD_NUMBER: _ClassVar[int]
    ok: bool
    detail: str
    png: bytes
    width: int
    height: int
    resolution: float
    origin_x: float
    origin_y: float
    frame_id: str
    has_robot_pose: bool
    robot_x: float
    robot_y: float
    robot_yaw: float
    footprint_polygon_xy: _containers.RepeatedScalarFieldContainer[float]
    def __init__(self, ok: _Optional[bool] = ..., detail: _Optional[str] = ..., png: _Optional[bytes] = ..., width: _Optional[int] = ..., height: _Optional[int] = ..., resolution: _Optional[float] = ..., origin_x: _Optional[float] = ..., origin_y: _Optional[float] = ..., frame_id: _Optional[str] = ..., has_robot_pose: _Optional[bool] = ..., robot_x: _Optional[float] = ..., robot_y: _Optional[float] = ..., robot_yaw: _Optional[float] = ..., footprint_polygon_xy: _Optional[_Iterable[float]] = ...) -> None: ...
