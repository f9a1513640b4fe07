"""Real processes for the SLAM provider tests: an in-process atlas, the HAL and the SLAM provider as children.

Every child is found through the atlas like any consumer would find it, driven over its lifecycle
Driver, and stopped by its own PID (SIGTERM, SIGKILL after a grace period); the fixtures assert none is
left behind. Deadlines are generous: the machine is shared and has two cores. The helpers live in
tests/support.
"""

from __future__ import annotations

from typing import Any

from support.fixtures import atlas, procs_fixture
from support.procs import ACTIVATE, DEACTIVATE, HAL, INIT, REPO, SLAM, Proc
from support.wait import wait_until

__all__ = ["ACTIVATE", "DEACTIVATE", "HAL", "HAL_CONFIG", "INIT", "REPO", "SLAM", "Proc", "atlas", "wait_until"]

# A small closed room with a few boxes: quick to map, distinctive enough to localize in.
SCENE: dict[str, Any] = {
    "name": "slam_test_room", "bounds": [0, 0, 6, 5],
    "walls": [{"start": a, "end": b, "thickness": 0.1, "height": 2.0}
              for a, b in (([0, 0], [6, 0]), ([6, 0], [6, 5]), ([6, 5], [0, 5]), ([0, 5], [0, 0]))],
    "boxes": [{"name": "crate", "center": [4.2, 1.2], "size": [0.6, 0.8], "height": 0.8},
              {"name": "shelf", "center": [1.0, 3.9], "size": [1.2, 0.4], "height": 1.5},
              {"name": "pillar", "center": [3.3, 3.4], "size": [0.3, 0.3], "height": 2.0}],
    "start": {"x": 1.5, "y": 1.5, "yaw": 0.0},
}
HAL_CONFIG: dict[str, Any] = {"scene": SCENE, "real_time_factor": 4.0, "odom_noise": "none",
                              "lidar_noise": {"noise_std": 0.0, "dropout_prob": 0.0}}


class SlamTestProc(Proc):
    """A provider child of this directory (``procs(cmd, name, **env)``); stopped newest first at module end."""

    consumer_id = "slam_test"
    ready_timeout_s = 90.0
    driver_timeout_s = 120.0


procs = procs_fixture(SlamTestProc)
