"""Score a replay against the live run it came from, from two recordings (the replay round trip).

From a recording we take the last /map and the SLAM trajectory: map->odom (SLAM, on /tf) composed with
odom->base_link (chassis, on /tf, interpolated) at each ground-truth odometry stamp. The live recording
holds /ground_truth/odom (``rbnx demo --record`` adds it); the replay runs on the same sim clock, so
its trajectory is scored at the same stamps. Metrics are slam_service.core.metrics' (occupied-cell IoU
with one cell of tolerance, ATE in the common start frame).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from robonix_common.geometry import compose, quat_to_yaw


@dataclass
class RunData:
    grid_msg: Any = None
    map_odom: list[tuple[float, float, float, float]] = field(default_factory=list)  # t, x, y, yaw
    odom_base: list[tuple[float, float, float, float]] = field(default_factory=list)
    gt: list[tuple[float, float, float, float]] = field(default_factory=list)


def _t(stamp: Any) -> float:
    return stamp.sec + stamp.nanosec * 1e-9


def _xyyaw(tr: Any) -> tuple[float, float, float]:
    q = tr.rotation
    return tr.translation.x, tr.translation.y, quat_to_yaw(q.x, q.y, q.z, q.w)


def load_run(path: str | Path, map_frame: str = "map", odom_frame: str = "odom",
             base_frame: str = "base_link") -> RunData:
    """Read one of our recordings (or any ROS 2 bag with these topics) with rosbags."""
    from rosbags.rosbag2 import Reader

    from rbnx.rosmsg import type_by_name

    run = RunData()
    with Reader(Path(path)) as reader:
        conns = [c for c in reader.connections if c.topic in ("/map", "/tf", "/ground_truth/odom")]
        for conn, _ts, raw in reader.messages(connections=conns):
            msg = type_by_name(conn.msgtype).deserialize(raw)  # type: ignore[union-attr]
            if conn.topic == "/map":
                run.grid_msg = msg
            elif conn.topic == "/ground_truth/odom":
                p = msg.pose.pose
                run.gt.append((_t(msg.header.stamp), p.position.x, p.position.y,
                               quat_to_yaw(p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w)))
            else:
                for tf in msg.transforms:
                    parent, child = tf.header.frame_id.strip("/"), tf.child_frame_id.strip("/")
                    if (parent, child) == (map_frame, odom_frame):
                        run.map_odom.append((_t(tf.header.stamp), *_xyyaw(tf.transform)))
                    elif (parent, child) == (odom_frame, base_frame):
                        run.odom_base.append((_t(tf.header.stamp), *_xyyaw(tf.transform)))
    for series in (run.map_odom, run.odom_base, run.gt):
        series.sort()
    return run


def _interp(series: np.ndarray, t: np.ndarray) -> np.ndarray:
    yaw = np.unwrap(series[:, 3])
    return np.stack([np.interp(t, series[:, 0], series[:, 1]), np.interp(t, series[:, 0], series[:, 2]),
                     np.interp(t, series[:, 0], yaw)], axis=1)


def trajectory(run: RunData, times: np.ndarray) -> np.ndarray:
    """map->base_link at ``times``: the latest map->odom at or before t, composed with odom->base at t."""
    if not run.map_odom or not run.odom_base:
        raise ValueError("recording has no map->odom or no odom->base_link transforms on /tf")
    mo = np.asarray(run.map_odom)
    ob = _interp(np.asarray(run.odom_base), times)
    idx = np.clip(np.searchsorted(mo[:, 0], times, side="right") - 1, 0, len(mo) - 1)
    return np.array([compose(mo[i, 1:], ob[k]) for k, i in enumerate(idx)])


def compare(live: RunData, replay: RunData) -> dict[str, float]:
    """IoU of the replay's final map with the live one, and both runs' ATE against the live ground truth."""
    from robonix_api.dds.convert import msg_to_grid
    from slam_service.core.metrics import ate_rmse, occupied_iou

    if live.grid_msg is None or replay.grid_msg is None:
        raise ValueError("a recording has no /map")
    if not live.gt:
        raise ValueError("the live recording has no /ground_truth/odom")
    gt = np.asarray(live.gt)
    lo = max(live.map_odom[0][0], replay.map_odom[0][0], live.odom_base[0][0], replay.odom_base[0][0])
    hi = min(live.odom_base[-1][0], replay.odom_base[-1][0])
    gt = gt[(gt[:, 0] >= lo) & (gt[:, 0] <= hi)]
    if len(gt) < 10:
        raise ValueError(f"runs overlap in only {len(gt)} ground-truth samples")
    g_live, g_rep = msg_to_grid(live.grid_msg), msg_to_grid(replay.grid_msg)
    ate_live = ate_rmse(trajectory(live, gt[:, 0]), gt[:, 1:])
    ate_replay = ate_rmse(trajectory(replay, gt[:, 0]), gt[:, 1:])
    return {"map_iou": occupied_iou(g_rep, g_live, tolerance_cells=1),
            "map_iou_exact": occupied_iou(g_rep, g_live, tolerance_cells=0),
            "ate_live_m": ate_live, "ate_replay_m": ate_replay,
            "ate_diff_m": abs(ate_replay - ate_live), "samples": float(len(gt)),
            "sim_span_s": float(gt[-1, 0] - gt[0, 0]) if math.isfinite(gt[-1, 0]) else 0.0}
