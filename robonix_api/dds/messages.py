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
from cyclonedds.idl.types import array, float32, float64, int8, int32, sequence, uint8, uint32, uint64

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
    """builtin_interfaces/Time: seconds and nanoseconds."""
    sec: int32 = 0
    nanosec: uint32 = 0

    @classmethod
    def from_sec(cls, t: float) -> "Time":
        """Float seconds -> Time; nanosec always in [0, 1e9) also for negative t."""
        ns = int(round(t * 1e9))
        return cls(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)

    def to_sec(self) -> float:
        """The time in float seconds."""
        return self.sec + self.nanosec * 1e-9


@final
@dataclass
class Duration(IdlStruct, typename="builtin_interfaces::msg::dds_::Duration_"):
    """builtin_interfaces/Duration: seconds and nanoseconds."""
    sec: int32 = 0
    nanosec: uint32 = 0

    def to_sec(self) -> float:
        """The duration in float seconds."""
        return self.sec + self.nanosec * 1e-9


# --- std_msgs -------------------------------------------------------------------------------------
@final
@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    """std_msgs/Header: stamp and frame of the data that follows."""
    stamp: Time = field(default_factory=Time)
    frame_id: str = ""


# --- geometry_msgs --------------------------------------------------------------------------------
@final
@dataclass
class Point(IdlStruct, typename="geometry_msgs::msg::dds_::Point_"):
    """geometry_msgs/Point (float64)."""
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0


@final
@dataclass
class Point32(IdlStruct, typename="geometry_msgs::msg::dds_::Point32_"):
    """geometry_msgs/Point32 (float32, for polygons)."""
    x: float32 = 0.0
    y: float32 = 0.0
    z: float32 = 0.0


@final
@dataclass
class Vector3(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    """geometry_msgs/Vector3."""
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0


@final
@dataclass
class Quaternion(IdlStruct, typename="geometry_msgs::msg::dds_::Quaternion_"):
    """geometry_msgs/Quaternion (x, y, z, w; identity by default)."""
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0
    w: float64 = 1.0


@final
@dataclass
class Pose(IdlStruct, typename="geometry_msgs::msg::dds_::Pose_"):
    """geometry_msgs/Pose: position and orientation."""
    position: Point = field(default_factory=Point)
    orientation: Quaternion = field(default_factory=Quaternion)


@final
@dataclass
class Pose2D(IdlStruct, typename="geometry_msgs::msg::dds_::Pose2D_"):
    """geometry_msgs/Pose2D: x, y, theta."""
    x: float64 = 0.0
    y: float64 = 0.0
    theta: float64 = 0.0


@final
@dataclass
class PoseStamped(IdlStruct, typename="geometry_msgs::msg::dds_::PoseStamped_"):
    """geometry_msgs/PoseStamped: a pose in a frame at a time."""
    header: Header = field(default_factory=Header)
    pose: Pose = field(default_factory=Pose)


@final
@dataclass
class PoseWithCovariance(IdlStruct, typename="geometry_msgs::msg::dds_::PoseWithCovariance_"):
    """geometry_msgs/PoseWithCovariance: a pose and its 6x6 row-major covariance."""
    pose: Pose = field(default_factory=Pose)
    covariance: array[float64, 36] = field(default_factory=_cov)


@final
@dataclass
class PoseWithCovarianceStamped(IdlStruct, typename="geometry_msgs::msg::dds_::PoseWithCovarianceStamped_"):
    """geometry_msgs/PoseWithCovarianceStamped (what /initialpose carries)."""
    header: Header = field(default_factory=Header)
    pose: PoseWithCovariance = field(default_factory=PoseWithCovariance)


@final
@dataclass
class Twist(IdlStruct, typename="geometry_msgs::msg::dds_::Twist_"):
    """geometry_msgs/Twist: linear and angular velocity (what /cmd_vel carries)."""
    linear: Vector3 = field(default_factory=Vector3)
    angular: Vector3 = field(default_factory=Vector3)


@final
@dataclass
class TwistStamped(IdlStruct, typename="geometry_msgs::msg::dds_::TwistStamped_"):
    """geometry_msgs/TwistStamped: a velocity in a frame at a time."""
    header: Header = field(default_factory=Header)
    twist: Twist = field(default_factory=Twist)


@final
@dataclass
class TwistWithCovariance(IdlStruct, typename="geometry_msgs::msg::dds_::TwistWithCovariance_"):
    """geometry_msgs/TwistWithCovariance: a velocity and its 6x6 covariance."""
    twist: Twist = field(default_factory=Twist)
    covariance: array[float64, 36] = field(default_factory=_cov)


@final
@dataclass
class Transform(IdlStruct, typename="geometry_msgs::msg::dds_::Transform_"):
    """geometry_msgs/Transform: translation and rotation."""
    translation: Vector3 = field(default_factory=Vector3)
    rotation: Quaternion = field(default_factory=Quaternion)


@final
@dataclass
class TransformStamped(IdlStruct, typename="geometry_msgs::msg::dds_::TransformStamped_"):
    """geometry_msgs/TransformStamped: parent frame (header), child frame and the transform."""
    header: Header = field(default_factory=Header)
    child_frame_id: str = ""
    transform: Transform = field(default_factory=Transform)


@final
@dataclass
class Polygon(IdlStruct, typename="geometry_msgs::msg::dds_::Polygon_"):
    """geometry_msgs/Polygon: a closed outline (footprints)."""
    points: sequence[Point32] = field(default_factory=list)


@final
@dataclass
class PolygonStamped(IdlStruct, typename="geometry_msgs::msg::dds_::PolygonStamped_"):
    """geometry_msgs/PolygonStamped: a polygon in a frame at a time."""
    header: Header = field(default_factory=Header)
    polygon: Polygon = field(default_factory=Polygon)


# --- nav_msgs -------------------------------------------------------------------------------------
@final
@dataclass
class Odometry(IdlStruct, typename="nav_msgs::msg::dds_::Odometry_"):
    """nav_msgs/Odometry: pose in the odom frame and twist in the child frame, with covariances."""
    header: Header = field(default_factory=Header)
    child_frame_id: str = ""
    pose: PoseWithCovariance = field(default_factory=PoseWithCovariance)
    twist: TwistWithCovariance = field(default_factory=TwistWithCovariance)


@final
@dataclass
class MapMetaData(IdlStruct, typename="nav_msgs::msg::dds_::MapMetaData_"):
    """nav_msgs/MapMetaData: load time, resolution, size and origin of a grid."""
    map_load_time: Time = field(default_factory=Time)
    resolution: float32 = 0.0
    width: uint32 = 0
    height: uint32 = 0
    origin: Pose = field(default_factory=Pose)


@final
@dataclass
class OccupancyGrid(IdlStruct, typename="nav_msgs::msg::dds_::OccupancyGrid_"):
    """nav_msgs/OccupancyGrid: row-major cells, -1 unknown, 0..100 occupancy."""
    header: Header = field(default_factory=Header)
    info: MapMetaData = field(default_factory=MapMetaData)
    data: sequence[int8] = field(default_factory=_i8)


@final
@dataclass
class Path(IdlStruct, typename="nav_msgs::msg::dds_::Path_"):
    """nav_msgs/Path: a planned path as stamped poses."""
    header: Header = field(default_factory=Header)
    poses: sequence[PoseStamped] = field(default_factory=list)


# --- sensor_msgs ----------------------------------------------------------------------------------
@final
@dataclass
class LaserScan(IdlStruct, typename="sensor_msgs::msg::dds_::LaserScan_"):
    """sensor_msgs/LaserScan: one sweep of ranges (and intensities) with its angles and limits."""
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


def _u8() -> np.ndarray:
    return np.zeros(0, dtype=np.uint8)


@final
@dataclass
class PointField(IdlStruct, typename="sensor_msgs::msg::dds_::PointField_"):
    """sensor_msgs/PointField: one field of a PointCloud2 point (datatype 7 = FLOAT32)."""
    name: str = ""
    offset: uint32 = 0
    datatype: uint8 = 0
    count: uint32 = 0


@final
@dataclass
class PointCloud2(IdlStruct, typename="sensor_msgs::msg::dds_::PointCloud2_"):
    """sensor_msgs/PointCloud2: packed points (robonix/primitive/lidar/lidar3d)."""
    header: Header = field(default_factory=Header)
    height: uint32 = 0
    width: uint32 = 0
    fields: sequence[PointField] = field(default_factory=list)
    is_bigendian: bool = False
    point_step: uint32 = 0
    row_step: uint32 = 0
    data: sequence[uint8] = field(default_factory=_u8)
    is_dense: bool = False


# --- tf2_msgs / rosgraph_msgs ---------------------------------------------------------------------
@final
@dataclass
class TFMessage(IdlStruct, typename="tf2_msgs::msg::dds_::TFMessage_"):
    """tf2_msgs/TFMessage: what /tf and /tf_static carry."""
    transforms: sequence[TransformStamped] = field(default_factory=list)


@final
@dataclass
class Clock(IdlStruct, typename="rosgraph_msgs::msg::dds_::Clock_"):
    """rosgraph_msgs/Clock: what /clock carries (simulated time)."""
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
    TFMessage, Clock, MapLifecycle, PointField, PointCloud2,
)

for _t in ALL_TYPES:
    _fastpath.install(_t)
