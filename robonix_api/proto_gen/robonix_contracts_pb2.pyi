from google.protobuf import empty_pb2 as _empty_pb2
from . import geometry_msgs_pb2 as _geometry_msgs_pb2
from . import lifecycle_pb2 as _lifecycle_pb2
from . import map_pb2 as _map_pb2
from . import nav_msgs_pb2 as _nav_msgs_pb2
from . import navigation_pb2 as _navigation_pb2
from . import sensor_msgs_pb2 as _sensor_msgs_pb2
from . import sim_pb2 as _sim_pb2
from google.protobuf import descriptor as _descriptor
from typing import ClassVar as _ClassVar

DESCRIPTOR: _descriptor.FileDescriptor
