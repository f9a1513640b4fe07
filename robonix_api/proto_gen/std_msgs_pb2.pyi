from . import builtin_interfaces_pb2 as _builtin_interfaces_pb2
from google.protobuf import descriptor as _descriptor
from google.protobuf import message as _message
from collections.abc import Mapping as _Mapping
from typing import ClassVar as _ClassVar, Optional as _Optional, Union as _Union

DESCRIPTOR: _descriptor.FileDescriptor

class Header(_message.Message):
    __slots__ = ("stamp", "frame_id")
    STAMP_FIELD_NUMBER: _ClassVar[int]
    FRAME_ID_FIELD_NUMBER: _ClassVar[int]
    stamp: _builtin_interfaces_pb2.Time
    frame_id: str
    def __init__(self, stamp: _Optional[_Union[_builtin_interfaces_pb2.Time, _Mapping]] = ..., frame_id: _Optional[str] = ...) -> None: ...

class String(_message.Message):
    __slots__ = ("data",)
    DATA_FIELD_NUMBER: _ClassVar[int]
    data: str
    def __init__(self, data: _Optional[str] = ...) -> None: ...
