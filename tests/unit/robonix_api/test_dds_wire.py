"""Byte-level CDR layouts: what we serialise must equal what rmw_cyclonedds puts on the wire.

XCDR1, little endian: 4-byte encapsulation header 00 01 00 00 (CDR_LE), then each primitive aligned to
its size (8 for float64) relative to the first byte after the header; strings are uint32 length
including the NUL, then the bytes and NUL; sequences are a uint32 count then the elements. What a real
Cyclone writer emits is checked in tests/integration/robonix_api/test_dds_wire_writer.py.
"""

from __future__ import annotations

import struct

import numpy as np
import pytest

import robonix_api.dds.messages as m

HDR = b"\x00\x01\x00\x00"


def cdr_string(s: str) -> bytes:
    b = s.encode() + b"\x00"
    return struct.pack("<I", len(b)) + b


def pad(buf: bytes, align: int) -> bytes:
    """Pad the body (after the 4-byte header) to ``align``."""
    body = len(buf) - 4
    return buf + b"\x00" * ((-body) % align)


def test_header() -> None:
    msg = m.Header(stamp=m.Time(sec=1_700_000_000, nanosec=123), frame_id="map")
    want = HDR + struct.pack("<iI", 1_700_000_000, 123) + cdr_string("map")
    assert msg.serialize() == want
    assert want.hex() == "00010000" "00f15365" "7b000000" "04000000" "6d617000"


def test_twist() -> None:
    msg = m.Twist(linear=m.Vector3(0.5, -0.25, 0.0), angular=m.Vector3(0.0, 0.0, 1.9))
    want = HDR + struct.pack("<6d", 0.5, -0.25, 0.0, 0.0, 0.0, 1.9)
    assert msg.serialize() == want
    assert len(want) == 4 + 48


def test_laser_scan() -> None:
    msg = m.LaserScan(header=m.Header(stamp=m.Time(5, 6), frame_id="laser"), angle_min=-1.0, angle_max=1.0,
                      angle_increment=0.5, time_increment=0.0, scan_time=0.1, range_min=0.05, range_max=12.0,
                      ranges=np.array([1.0, 2.0, np.inf, 0.5, 3.0], np.float32), intensities=[7.0])
    want = HDR + struct.pack("<iI", 5, 6) + cdr_string("laser")  # body at 16: 4-aligned for float32
    assert len(want) - 4 == 18
    want = pad(want, 4) + struct.pack("<7f", -1.0, 1.0, 0.5, 0.0, 0.1, 0.05, 12.0)
    want += struct.pack("<I5f", 5, 1.0, 2.0, np.inf, 0.5, 3.0) + struct.pack("<If", 1, 7.0)
    assert msg.serialize() == want


def test_occupancy_grid() -> None:
    info = m.MapMetaData(map_load_time=m.Time(3, 4), resolution=0.05, width=3, height=2,
                         origin=m.Pose(m.Point(-1.0, -2.0, 0.0), m.Quaternion(0.0, 0.0, 0.0, 1.0)))
    data = np.array([-1, 0, 100, 50, -1, 1], np.int8)
    msg = m.OccupancyGrid(header=m.Header(stamp=m.Time(1, 2), frame_id="map"), info=info, data=data)
    want = HDR + struct.pack("<iI", 1, 2) + cdr_string("map")  # body 16
    want += struct.pack("<iI", 3, 4) + struct.pack("<fII", 0.05, 3, 2)  # body 36
    want = pad(want, 8) + struct.pack("<7d", -1.0, -2.0, 0.0, 0.0, 0.0, 0.0, 1.0)  # float64 at body 40
    want += struct.pack("<I", 6) + data.tobytes()
    assert msg.serialize() == want
    assert msg.serialize()[4 + 36:4 + 40] == b"\x00" * 4  # the alignment gap ROS also leaves


def test_tf_message() -> None:
    ts = m.TransformStamped(header=m.Header(stamp=m.Time(7, 8), frame_id="odom"), child_frame_id="base_link",
                            transform=m.Transform(m.Vector3(1.0, 2.0, 0.0), m.Quaternion(0.0, 0.0, 0.6, 0.8)))
    msg = m.TFMessage(transforms=[ts, ts])
    want = HDR + struct.pack("<I", 2)
    for _ in range(2):
        want = pad(want, 4) + struct.pack("<iI", 7, 8) + cdr_string("odom")  # "odom\0" ends unaligned
        want = pad(want, 4) + cdr_string("base_link")  # string length is a uint32: 4-aligned
        want = pad(want, 8) + struct.pack("<7d", 1.0, 2.0, 0.0, 0.0, 0.0, 0.6, 0.8)
    assert msg.serialize() == want


def test_clock_odometry_polygon_covariance() -> None:
    assert m.Clock(clock=m.Time(9, 10)).serialize() == HDR + struct.pack("<iI", 9, 10)
    cov = np.arange(36, dtype=float)
    pwc = m.PoseWithCovariance(covariance=cov)
    assert pwc.serialize() == HDR + struct.pack("<7d", 0, 0, 0, 0, 0, 0, 1) + cov.astype("<f8").tobytes()
    poly = m.Polygon(points=[m.Point32(1.0, 2.0, 3.0)])
    assert poly.serialize() == HDR + struct.pack("<I3f", 1, 1.0, 2.0, 3.0)
    odom = m.Odometry(header=m.Header(frame_id="odom"), child_frame_id="base_link")
    want = pad(HDR + struct.pack("<iI", 0, 0) + cdr_string("odom"), 4) + cdr_string("base_link")
    want = pad(want, 8) + struct.pack("<7d", 0, 0, 0, 0, 0, 0, 1) + bytes(36 * 8)
    want += bytes(6 * 8) + bytes(36 * 8)
    assert odom.serialize() == want


TYPE_NAMES = {
    m.Time: "builtin_interfaces::msg::dds_::Time_", m.Header: "std_msgs::msg::dds_::Header_",
    m.Twist: "geometry_msgs::msg::dds_::Twist_", m.LaserScan: "sensor_msgs::msg::dds_::LaserScan_",
    m.OccupancyGrid: "nav_msgs::msg::dds_::OccupancyGrid_", m.TFMessage: "tf2_msgs::msg::dds_::TFMessage_",
    m.Clock: "rosgraph_msgs::msg::dds_::Clock_", m.Odometry: "nav_msgs::msg::dds_::Odometry_",
    m.PoseWithCovarianceStamped: "geometry_msgs::msg::dds_::PoseWithCovarianceStamped_",
}


@pytest.mark.parametrize("t", list(TYPE_NAMES))
def test_type_names(t: type) -> None:
    assert t.__idl__.idl_transformed_typename == TYPE_NAMES[t]


@pytest.mark.parametrize("t", m.ALL_TYPES, ids=lambda t: t.__name__)
def test_roundtrip_final_xcdr1(t: type) -> None:
    """Every type is @final, serialises with the CDR_LE header and survives a round trip."""
    assert t.__idl__.xcdrv1_head == 0
    assert t.__idl__.default_version == 1
    raw = t().serialize()
    assert raw[:4] == HDR
    back = t.deserialize(raw)
    assert back.serialize() == raw


def test_numeric_fields_arrive_as_numpy() -> None:
    raw = m.LaserScan(ranges=[1.0, 2.0]).serialize()
    back = m.LaserScan.deserialize(raw)
    assert isinstance(back.ranges, np.ndarray)
    assert back.ranges.dtype == np.float32
    back.ranges[0] = 5.0  # writable copy, not a view of the receive buffer
    grid = m.OccupancyGrid.deserialize(m.OccupancyGrid(data=np.arange(-5, 5, dtype=np.int8)).serialize())
    assert grid.data.dtype == np.int8
    assert grid.data.tolist() == list(range(-5, 5))
