"""PointCloud2 -> planar scan: a cloud built and serialized by rosbags (its own sensor_msgs/PointCloud2) decodes
with our IDL struct, unpacks to the points put in, and bins into the nearest range per bearing within the
height band, as pointcloud_to_laserscan does."""

from __future__ import annotations

import math

import numpy as np
import pytest

from robonix_api.dds.messages import PointCloud2
from robonix_common.pointcloud import FLOAT32, CloudLayoutError, ScanBand, planar_scan, xyz_from_packed

# three points in the band (at bearings 0, 90 and -90 degrees), one above and one below it, one farther
# behind a nearer one, one NaN
POINTS = np.array([[2.0, 0.0, 0.0], [0.0, 3.0, 0.05], [0.0, -1.5, -0.05], [1.0, 1.0, 0.5], [1.0, 1.0, -0.5],
                   [4.0, 0.01, 0.0], [math.nan, 0.0, 0.0]], dtype=np.float32)


def _rosbags_cloud() -> bytes:
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    t = store.types
    fields = [t["sensor_msgs/msg/PointField"](name=n, offset=4 * i, datatype=FLOAT32, count=1)
              for i, n in enumerate(("x", "y", "z"))]
    fields.append(t["sensor_msgs/msg/PointField"](name="intensity", offset=12, datatype=FLOAT32, count=1))
    packed = np.hstack([POINTS, np.ones((len(POINTS), 1), np.float32)]).astype("<f4").tobytes()
    msg = t["sensor_msgs/msg/PointCloud2"](
        header=t["std_msgs/msg/Header"](stamp=t["builtin_interfaces/msg/Time"](sec=1, nanosec=0), frame_id="lidar"),
        height=1, width=len(POINTS), fields=fields, is_bigendian=False, point_step=16,
        row_step=16 * len(POINTS), data=np.frombuffer(packed, np.uint8), is_dense=False)
    return bytes(store.serialize_cdr(msg, "sensor_msgs/msg/PointCloud2"))


def test_rosbags_cloud_decodes_and_bins_into_a_scan() -> None:
    cloud = PointCloud2.deserialize(_rosbags_cloud())
    assert (cloud.header.frame_id, cloud.width, cloud.point_step) == ("lidar", len(POINTS), 16)
    fields = {f.name: (f.offset, f.datatype) for f in cloud.fields}
    xyz = xyz_from_packed(cloud.data, cloud.width * cloud.height, cloud.point_step, fields, cloud.is_bigendian)
    np.testing.assert_array_equal(xyz[:6], POINTS[:6].astype(np.float64))
    band = ScanBand(min_height=-0.1, max_height=0.1, angle_increment=math.radians(1.0))
    ranges = planar_scan(xyz, band)
    assert ranges.shape == (360,)
    bearing = {round(math.degrees(band.angle_min + i * band.angle_increment)): r for i, r in enumerate(ranges)}
    assert bearing[0] == pytest.approx(2.0)  # the nearer of the two points ahead
    assert bearing[90] == pytest.approx(3.0)
    assert bearing[-90] == pytest.approx(1.5)
    assert math.isinf(bearing[45])  # the points at 45 degrees are outside the height band
    assert np.isfinite(ranges).sum() == 3
    # a cloud of our own struct round-trips through the same path
    assert PointCloud2.deserialize(cloud.serialize()).data.tobytes() == cloud.data.tobytes()


def test_no_inf_and_layout_errors() -> None:
    ranges = planar_scan(np.zeros((0, 3)), ScanBand(use_inf=False, range_max=10.0, inf_epsilon=1.0))
    assert set(ranges.tolist()) == {11.0}
    with pytest.raises(CloudLayoutError, match="no z field"):
        xyz_from_packed(b"\0" * 8, 1, 8, {"x": (0, FLOAT32), "y": (4, FLOAT32)})
    with pytest.raises(CloudLayoutError, match="datatype 2"):
        xyz_from_packed(b"\0" * 12, 1, 12, {"x": (0, 2), "y": (4, FLOAT32), "z": (8, FLOAT32)})
    with pytest.raises(CloudLayoutError, match="need more"):
        xyz_from_packed(b"\0" * 12, 2, 12, {"x": (0, FLOAT32), "y": (4, FLOAT32), "z": (8, FLOAT32)})
