"""TF buffer: chaining, interpolation, latest-common-time, and the errors."""

from __future__ import annotations

import math

import pytest

from robonix_api.dds import ConnectivityError, ExtrapolationError, FrameNotFoundError, TfBuffer, TfError


@pytest.fixture
def buf() -> TfBuffer:
    b = TfBuffer(cache_s=10.0)
    b.set_pose2d("map", "odom", 1.0, 0.0, 0.0, 10.0)
    b.set_pose2d("map", "odom", 2.0, 0.0, math.pi / 2, 12.0)
    b.set_pose2d("odom", "base_link", 0.0, 0.0, 0.0, 9.0)
    b.set_pose2d("odom", "base_link", 4.0, 0.0, 0.0, 13.0)
    b.set_pose2d("base_link", "laser", 0.2, 0.0, 0.0, 0.0, static=True)
    return b


def test_interpolation_through_odom(buf: TfBuffer) -> None:
    # t=11: map->odom halfway: x=1.5, yaw=pi/4 (slerp); odom->base_link: x=2.0
    x, y, yaw = buf.lookup_pose2d("map", "base_link", 11.0)
    assert yaw == pytest.approx(math.pi / 4)
    assert x == pytest.approx(1.5 + 2.0 * math.cos(math.pi / 4))
    assert y == pytest.approx(2.0 * math.sin(math.pi / 4))
    assert buf.lookup("map", "base_link", 11.0) == pytest.approx((x, y, yaw))


def test_latest_common_time_and_static(buf: TfBuffer) -> None:
    tf = buf.lookup_transform("map", "laser")  # latest common time = min(12, 13) = 12
    assert tf.stamp == pytest.approx(12.0)
    x, y, yaw = tf.to_pose2d()
    # odom->base_link at 12: x=3.0; rotated by pi/2 -> (0, 3) + (2, 0); laser 0.2 ahead along yaw
    assert (x, y, yaw) == pytest.approx((2.0, 3.2, math.pi / 2))


def test_inverse_lookup(buf: TfBuffer) -> None:
    fwd = buf.lookup_transform("map", "laser", 11.5)
    inv = buf.lookup_transform("laser", "map", 11.5)
    ident = (fwd * inv).to_pose2d()
    assert ident == pytest.approx((0.0, 0.0, 0.0), abs=1e-9)


def test_unknown_frame_names_it_and_lists_known(buf: TfBuffer) -> None:
    with pytest.raises(FrameNotFoundError) as e:
        buf.lookup("map", "base_footprint")
    assert "base_footprint" in str(e.value)
    assert "odom" in str(e.value)
    assert "laser" in str(e.value)
    assert isinstance(e.value, TfError)
    assert isinstance(e.value, LookupError)


def test_extrapolation_says_requested_and_available(buf: TfBuffer) -> None:
    with pytest.raises(ExtrapolationError) as e:
        buf.lookup("map", "base_link", 20.0)
    msg = str(e.value)
    assert "20.000000" in msg
    assert "10.000000" in msg
    assert "12.000000" in msg
    assert "future" in msg
    with pytest.raises(ExtrapolationError, match="past"):
        buf.lookup("map", "base_link", 5.0)


def test_not_connected(buf: TfBuffer) -> None:
    buf.set_pose2d("world", "elsewhere", 0, 0, 0, 10.0)
    with pytest.raises(ConnectivityError):
        buf.lookup("map", "elsewhere", 10.0)


def test_cache_prunes_old_stamps() -> None:
    b = TfBuffer(cache_s=1.0)
    for i in range(50):
        b.set_pose2d("odom", "base_link", i * 0.1, 0.0, 0.0, i * 0.1)
    with pytest.raises(ExtrapolationError):
        b.lookup("odom", "base_link", 1.0)
    assert b.lookup("odom", "base_link", 4.5)[0] == pytest.approx(4.5)


def test_same_frame_and_bad_input(buf: TfBuffer) -> None:
    assert buf.lookup("odom", "odom") == (0.0, 0.0, 0.0)
    with pytest.raises(ValueError, match="frames must be non-empty and differ"):
        buf.set_pose2d("a", "a", 0, 0, 0, 0)
