"""ROS 2-compatible data plane over Cyclone DDS: messages, QoS presets, nodes, TF, sim clock.

Nothing here needs ROS installed; a ROS 2 system on the same domain sees our topics as ROS topics
(``rt/<name>``, ``<pkg>::msg::dds_::<Type>_``, XCDR1 little-endian). See DESIGN.md §1 and §5.
"""

from robonix_api.dds.clock import ClockPublisher, SimClock
from robonix_api.dds.config import DdsConfigError, effective_config
from robonix_api.dds.messages import (
    Clock,
    Duration,
    Header,
    LaserScan,
    MapLifecycle,
    MapMetaData,
    OccupancyGrid,
    Odometry,
    Path,
    Point,
    Point32,
    Polygon,
    PolygonStamped,
    Pose,
    Pose2D,
    PoseStamped,
    PoseWithCovariance,
    PoseWithCovarianceStamped,
    Quaternion,
    TFMessage,
    Time,
    Transform,
    TransformStamped,
    Twist,
    TwistStamped,
    TwistWithCovariance,
    Vector3,
)
from robonix_api.dds.node import DdsNode, Publisher, Subscription, dds_topic_name
from robonix_api.dds.qos import QOS_NAMES, qos_profile
from robonix_api.dds.tf import (
    ConnectivityError,
    ExtrapolationError,
    FrameNotFoundError,
    StaticTfBroadcaster,
    TfBroadcaster,
    TfBuffer,
    TfError,
    Transform3,
    make_transform,
)
from robonix_api.dds.validate import validate_message

__all__ = [
    "Clock", "ClockPublisher", "ConnectivityError", "DdsConfigError", "DdsNode", "Duration", "ExtrapolationError",
    "FrameNotFoundError", "Header", "LaserScan", "MapLifecycle", "MapMetaData", "OccupancyGrid", "Odometry", "Path",
    "Point",
    "Point32", "Polygon", "PolygonStamped", "Pose", "Pose2D", "PoseStamped", "PoseWithCovariance",
    "PoseWithCovarianceStamped", "Publisher", "QOS_NAMES", "Quaternion", "SimClock", "StaticTfBroadcaster",
    "Subscription", "TFMessage", "TfBroadcaster", "TfBuffer", "TfError", "Time", "Transform", "Transform3",
    "TransformStamped", "Twist", "TwistStamped", "TwistWithCovariance", "Vector3", "dds_topic_name",
    "effective_config", "make_transform", "qos_profile", "validate_message",
]
