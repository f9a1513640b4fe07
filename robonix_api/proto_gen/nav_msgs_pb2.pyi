from . import builtin_interfaces_pb2 as _builtin_interfaces_pb2
from . import std_msgs_pb2 as _std_msgs_pb2
from . import geometry_msgs_pb2 as _geometry_msgs_pb2
from google.protobuf.internal import containers as _containers
from google.protobuf import descriptor as _descriptor
from google.protobuf import message as _message
from collections.abc import Iterable as _Iterable, Mapping as _Mapping
from typing import ClassVar as _ClassVar, Optional as _Optional, Union as _Union

DESCRIPTOR: _descriptor.FileDescriptor

class Odometry(_message.Message):
    __slots__ = ("header", "child_frame_id", "pose", "twist")
    HEADER_FIELD_NUMBER: _ClassVar[int]
    CHILD_FRAME_ID_FIELD_NUMBER: _ClassVar[int]
    POSE_FIELD_NUMBER: _ClassVar[int]
    TWIST_FIELD_NUMBER: _ClassVar[int]
    header: _std_msgs_pb2.Header
    child_frame_id: str
    pose: _geometry_msgs_pb2.PoseWithCovariance
    twist: _geometry_msgs_pb2.TwistWithCovariance
    def __init__(self, header: _Optional[_Union[_std_msgs_pb2.Header, _Mapping]] = ..., child_frame_id: _Optional[str] = ..., pose: _Optional[_Union[_geometry_msgs_pb2.PoseWithCovariance, _Mapping]] = ..., twist: _Optional[_Union[_geometry_msgs_pb2.TwistWithCovariance, _Mapping]] = ...) -> None: ...

class MapMetaData(_message.Message):
    __slots__ = ("map_load_time", "resolution", "width", "height", "origin")
    MAP_LOAD_TIME_FIELD_NUMBER: _ClassVar[int]
    RESOLUTION_FIELD_NUMBER: _ClassVar[int]
    WIDTH_FIELD_NUMBER: _ClassVar[int]
    HEIGHT_FIELD_NUMBER: _ClassVar[int]
    ORIGIN_FIELD_NUMBER: _ClassVar[int]
    map_load_time: _builtin_interfaces_pb2.Time
    resolution: float
    width: int
    height: int
    origin: _geometry_msgs_pb2.Pose
    def __init__(self, map_load_time: _Optional[_Union[_builtin_interfaces_pb2.Time, _Mapping]] = ..., resolution: _Optional[float] = ..., width: _Optional[int] = ..., height: _Optional[int] = ..., origin: _Optional[_Union[_geometry_msgs_pb2.Pose, _Mapping]] = ...) -> None: ...

class OccupancyGrid(_message.Message):
    __slots__ = ("header", "info", "data")
    HEADER_FIELD_NUMBER: _ClassVar[int]
    INFO_FIELD_NUMBER: _ClassVar[int]
    DATA_FIELD_NUMBER: _ClassVar[int]
    header: _std_msgs_pb2.Header
    info: MapMetaData
    data: _containers.RepeatedScalarFieldContainer[int]
    def __init__(self, header: _Optional[_Union[_std_msgs_pb2.Header, _Mapping]] = ..., info: _Optional[_Union[MapMetaData, _Mapping]] = ..., data: _Optional[_Iterable[int]] = ...) -> None: ...

class Path(_message.Message):
    __slots__ = ("header", "poses")
    HEADER_FIELD_NUMBER: _ClassVar[int]
    POSES_FIELD_NUMBER: _ClassVar[int]
    header: _std_msgs_pb2.Header
    poses: _containers.RepeatedCompositeFieldContainer[_geometry_msgs_pb2.PoseStamped]
    def __init__(self, header: _Optional[_Union[_std_msgs_pb2.Header, _Mapping]] = ..., poses: _Optional[_Iterable[_Union[_geometry_msgs_pb2.PoseStamped, _Mapping]]] = ...) -> None: ...
