"""`rbnx convert-carmen`: a CARMEN log as a rosbag2 that rosbags reads back with the log's stamps."""

from __future__ import annotations

import bz2
from pathlib import Path

import numpy as np

from rbnx.cli import main


def _log(path: Path) -> None:
    lines = []
    for k, t in enumerate([5.0, 5.01, 4.9, 5.3]):  # a burst and a line out of order, as real loggers write
        ranges = " ".join(f"{1.0 + 0.01 * (i + k):.2f}" for i in range(180))
        lines.append(f"FLASER 180 {ranges} {0.1 * k} 0 0 {0.1 * k} 0 0 {t:.6f} nohost 0.0")
    with bz2.open(path, "wt") as fh:
        fh.write("\n".join(lines) + "\n")


def test_round_trip_keeps_stamps_and_ranges(tmp_path: Path, capsys) -> None:
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore

    _log(tmp_path / "x.clf.bz2")
    assert main(["convert-carmen", str(tmp_path / "x.clf.bz2"), str(tmp_path / "bag")]) == 0
    ts = get_typestore(Stores.ROS2_HUMBLE)
    counts: dict[str, int] = {}
    stamps, logs, first = [], [], None
    with Reader(tmp_path / "bag") as r:
        for conn, t_ns, raw in r.messages():
            counts[conn.topic] = counts.get(conn.topic, 0) + 1
            if conn.topic == "/scan":
                msg = ts.deserialize_cdr(raw, conn.msgtype)
                stamps.append(msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec)
                logs.append(t_ns)
                first = msg if first is None else first
    assert counts == {"/scan": 4, "/odom": 4, "/tf": 4, "/tf_static": 1}
    np.testing.assert_allclose(stamps, [5.0, 5.01, 4.9, 5.3], atol=1e-6)  # file order, stamps untouched
    assert logs == sorted(logs)  # log times monotonic: replay keeps the file's order
    np.testing.assert_allclose(first.ranges[:3], [1.0, 1.01, 1.02], atol=1e-6)


def test_bad_input_is_exit_2(tmp_path: Path, capsys) -> None:
    assert main(["convert-carmen", str(tmp_path / "missing.clf"), str(tmp_path / "bag")]) == 2
    assert "no such log" in capsys.readouterr().err
