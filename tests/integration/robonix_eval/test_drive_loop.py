"""The shared scripted sim drive (robonix_eval.slam_loop.drive_loop) reports each waypoint it reaches.

bench/slam_lifelong.py cuts a route driven several times into laps from these reports, so they must come
once per waypoint, in order, including the last one (reached on the final control step of the drive), with
the distance driven so far.
"""

from __future__ import annotations

from robonix_eval.slam_loop import REALISTIC, drive_loop

# Out along the start heading and back, twice: short enough for a test, two "laps" of the same route.
ROUTE = [(3.8, 4.0), (3.8, 5.2), (3.8, 4.0), (2.5, 4.0)]


def test_drive_loop_reports_every_waypoint_with_distance_so_far() -> None:
    reached: list[tuple[int, float]] = []
    stamps: list[float] = []
    drive, _truth = drive_loop("apartment", REALISTIC, 0, ROUTE * 2, 40.0,
                               lambda scan, _odom, _gt, _wz: stamps.append(scan.stamp),
                               lambda i, driven: reached.append((i, driven)))
    assert drive.completed, drive
    assert [i for i, _ in reached] == list(range(1, 2 * len(ROUTE) + 1))
    driven = [d for _, d in reached]
    assert all(b > a for a, b in zip(driven, driven[1:], strict=False)), driven
    assert driven[-1] == drive.path_length  # the last report comes at the very end of the drive
    legs = 1.3 + 1.2 + 1.2 + 1.3
    assert abs(driven[len(ROUTE) - 1] - legs) < 0.5, driven  # one lap of the route ~ its polyline length
    assert stamps == sorted(stamps)
    assert len(stamps) > 20
