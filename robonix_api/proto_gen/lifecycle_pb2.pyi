from google.protobuf.internal import enum_type_wrapper as _enum_type_wrapper
from google.protobuf import descriptor as _descriptor
from google.protobuf import message as _message
from typing import ClassVar as _ClassVar, Optional as _Optional

DESCRIPTOR: _descriptor.FileDescriptor

class Driver_Request(_message.Message):
    __slots__ = ("command", "config_json")
    class Driver_RequestEnum(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
        __slots__ = ()
        CMD_INIT: _ClassVar[Driver_Request.Driver_RequestEnum]
        CMD_ACTIVATE: _ClassVar[Driver_Request.Driver_RequestEnum]
        CMD_DEACTIVATE: _ClassVar[Driver_Request.Driver_RequestEnum]
        CMD_SHUTDOWN: _ClassVar[Driver_Request.Driver_RequestEnum]
    CMD_INIT: Driver_Request.Driver_RequestEnum
    CMD_ACTIVATE: Driver_Request.Driver_RequestEnum
    CMD_DEACTIVATE: Driver_Request.Driver_RequestEnum
    CMD_SHUTDOWN: Driver_Request.Driver_RequestEnum
    COMMAND_FIELD_NUMBER: _ClassVar[int]
    CONFIG_JSON_FIELD_NUMBER: _ClassVar[int]
    command: int
    config_json: str
    def __init__(self, command: _Optional[int] = ..., config_json: _Optional[str] = ...) -> None: ...

class Driver_Response(_message.Message):
    __slots__ = ("ok", "state", "error")
    OK_FIELD_NUMBER: _ClassVar[int]
    STATE_FIELD_NUMBER: _ClassVar[int]
    ERROR_FIELD_NUMBER: _ClassVar[int]
    ok: bool
    state: str
    error: str
    def __init__(self, ok: _Optional[bool] = ..., state: _Optional[str] = ..., error: _Optional[str] = ...) -> None: ...
