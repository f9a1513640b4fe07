"""ROS 2 message types as Cyclone DDS IDL structs, wire-identical to rmw_cyclonedds.

Field order and types follow the ROS 2 ``.msg`` files exactly; type names are ROS 2's DDS names
(``<pkg>::msg::dds_::<Type>_``) so a ROS 2 node on the same domain sees ordinary ROS topics. All types
are ``@final`` (as rosidl-generated IDL is), which serialises as plain XCDR1 (encapsulation ``CDR_LE``).

Numeric sequences/arrays (``ranges``, ``data``, ``covariance`` …) accept lists or numpy arrays and are
delivered as numpy arrays: see ``_fastpath`` for why.
"""

from dataclasses import dataclass, field

import numpy as np
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.annotations import final
from cyclonedds.idl.types import array, float32, float64, int8, int32, sequence, uint32, uint64

from robonix_api.dds import _fastpath


def _cov() -> np.ndarray:
    return np.zeros(36, dtype=np.float64)


def _f32() -> np.ndarray:
    return np.zeros(0, dtype=np.float32)


def _i8() -> np.ndarray:
    return np.zeros(0, dtype=np.int8)


# --- builtin_interfaces ---------------------------------------------------------------------------
@final
@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: int32 = 0
    nanosec: uint32 = 0

    @classmethod
    def from_sec(cls, t: float) -> "Time":
        """Float seconds -> Time; nanosec always in [0, 1e9) also for negative t."""
        ns = int(round(t * 1e9))
        return cls(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)

    def to_sec(self) -> float:
        return self.sec + self.nanosec * 1e-9


@final
@dataclass
class Duration(IdlStruct, typename="builtin_interfaces::msg::dds_::Duration_"):
    sec: int32 = 0
    nanosec: uint32 = 0

    def to_sec(self) -> float:
        return self.sec + self.nanosec * 1e-9


# --- std_msgs -------------------------------------------------------------------------------------
@final
@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time = field(default_factory=Time)
    frame_id: str = ""


# --- geometry_msgs --------------------------------------------------------------------------------
@final
@dataclass
class Point(IdlStruct, typename="geometry_msgs::msg::dds_::Point_"):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0


@final
@dataclass
class Point32(IdlStruct, typename="geometry_msgs::msg::dds_::Point32_"):
    x: float32 = 0.0
    y: float32 = 0.0
    z: float32 = 0.0


@final
@dataclass
class Vector3(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0


@final
@dataclass
class Quaternion(IdlStruct, typename="geometry_msgs::msg::dds_::Quaternion_"):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0
    w: float64 = 1.0


@final
@dataclass
class Pose(IdlStruct, typename="geometry_msgs::msg::dds_::Pose_"):
    position: Point = field(default_factory=Point)
    orientation: Quaternion = field(default_factory=Quaternion)


@final
@dataclass
class Pose2D(IdlStruct, typename="geometry_msgs::msg::dds_::Pose2D_"):
    x: float64 = 0.0
    y: float64 = 0.0
    theta: float64 = 0.0


@final
@dataclass
class PoseStamped(IdlStruct, typename="geometry_msgs::msg::dds_::PoseStamped_"):
    header: Header = field(default_factory=Header)
    pose: Pose = field(default_factory=Pose)


@final
@dataclass
class PoseWithCovariance(IdlStruct, typename="geometry_msgs::msg::dds_::PoseWithCovariance_"):
    pose: Pose = field(default_factory=Pose)
    covariance: array[float64, 36] = field(default_factory=_cov)


@final
@dataclass
class PoseWithCovarianceStamped(IdlStruct, typename="geometry_msgs::msg::dds_::PoseWithCovarianceStamped_"):
    header: Header = field(default_factory=Header)
    pose: PoseWithCovariance = field(default_factory=PoseWithCovariance)


@final
@dataclass
class Twist(IdlStruct, typename="geometry_msgs::msg::dds_::Twist_"):
    linear: Vector3 = field(default_factory=Vector3)
    angular: Vector3 = field(default_factory=Vector3)


@final
@dataclass
class TwistStamped(IdlStruct, typename="geometry_msgs::msg::dds_::TwistStamped_"):
    header: Header = field(default_factory=Header)
    twist: Twist = field(default_factory=Twist)


@final
@dataclass
class TwistWithCovariance(IdlStruct, typename="geometry_msgs::msg::dds_::TwistWithCovariance_"):
    twist: Twist = field(default_factory=Twist)
    covariance: array[float64, 36] = field(default_factory=_cov)


@final
@dataclass
class Transform(IdlStruct, typename="geometry_msgs::msg::dds_::Transform_"):
    translation: Vector3 = field(default_factory=Vector3)
    rotation: Quaternion = field(default_factory=Quaternion)


@final
@dataclass
class TransformStamped(IdlStruct, typename="geometry_msgs::msg::dds_::TransformStamped_"):
    header: Header = field(default_factory=Header)
    child_frame_id: str = ""
    transform: Transform = field(default_factory=Transform)


@final
@dataclass
class Polygon(IdlStruct, typename="geometry_msgs::msg::dds_::Polygon_"):
    points: sequence[Point32] = field(default_factory=list)


@final
@dataclass
class PolygonStamped(IdlStruct, typename="geometry_msgs::msg::dds_::PolygonStamped_"):
    header: Header = field(default_factory=Header)
    polygon: Polygon = field(default_factory=Polygon)


# --- nav_msgs -------------------------------------------------------------------------------------
@final
@dataclass
class Odometry(IdlStruct, typename="nav_msgs::msg::dds_::Odometry_"):
    header: Header = field(default_factory=Header)
    child_frame_id: str = ""
    pose: PoseWithCovariance = field(default_factory=PoseWithCovariance)
    twist: TwistWithCovariance = field(default_factory=TwistWithCovariance)


@final
@dataclass
class MapMetaData(IdlStruct, typename="nav_msgs::msg::dds_::MapMetaData_"):
    map_load_time: Time = field(default_factory=Time)
    resolution: float32 = 0.0
    width: uint32 = 0
    height: uint32 = 0
    origin: Pose = field(default_factory=Pose)


@final
@dataclass
class OccupancyGrid(IdlStruct, typename="nav_msgs::msg::dds_::OccupancyGrid_"):
    header: Header = field(default_factory=Header)
    info: MapMetaData = field(default_factory=MapMetaData)
    data: sequence[int8] = field(default_factory=_i8)


@final
@dataclass
class Path(IdlStruct, typename="nav_msgs::msg::dds_::Path_"):
    header: Header = field(default_factory=Header)
    poses: sequence[PoseStamped] = field(default_factory=list)


# --- sensor_msgs ----------------------------------------------------------------------------------
@final
@dataclass
class LaserScan(IdlStruct, typename="sensor_msgs::msg::dds_::LaserScan_"):
    header: Header = field(default_factory=Header)
    angle_min: float32 = 0.0
    angle_max: float32 = 0.0
    angle_increment: float32 = 0.0
    time_increment: float32 = 0.0
    scan_time: float32 = 0.0
    range_min: float32 = 0.0
    range_max: float32 = 0.0
    ranges: sequence[float32] = field(default_factory=_f32)
    intensities: sequence[float32] = field(default_factory=_f32)


# --- tf2_msgs / rosgraph_msgs ---------------------------------------------------------------------
@final
@dataclass
class TFMessage(IdlStruct, typename="tf2_msgs::msg::dds_::TFMessage_"):
    transforms: sequence[TransformStamped] = field(default_factory=list)


@final
@dataclass
class Clock(IdlStruct, typename="rosgraph_msgs::msg::dds_::Clock_"):
    clock: Time = field(default_factory=Time)


# --- robonix map ----------------------------------------------------------------------------------
@final
@dataclass
class MapLifecycle(IdlStruct, typename="map::msg::dds_::MapLifecycle_"):
    """robonix/service/map/lifecycle (map/msg/MapLifecycle.msg): which map, in which mode, which generation."""

    map_id: str = ""
    mode: str = ""
    generation: uint64 = 0


ALL_TYPES = (
    Time, Duration, Header, Point, Point32, Vector3, Quaternion, Pose, Pose2D, PoseStamped,
    PoseWithCovariance, PoseWithCovarianceStamped, Twist, TwistStamped, TwistWithCovariance, Transform,
    TransformStamped, Polygon, PolygonStamped, Odometry, MapMetaData, OccupancyGrid, Path, LaserScan,
    TFMessage, Clock, MapLifecycle,
)

for _t in ALL_TYPES:
    _fastpath.install(_t)
