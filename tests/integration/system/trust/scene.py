"""A small room for the trust tests' HAL (quick to simulate; bounds [0, 0, 6, 5])."""

from __future__ import annotations

from typing import Any

SCENE: dict[str, Any] = {
    "name": "trust_room", "bounds": [0, 0, 6, 5],
    "walls": [{"start": a, "end": b, "thickness": 0.1, "height": 2.0}
              for a, b in (([0, 0], [6, 0]), ([6, 0], [6, 5]), ([6, 5], [0, 5]), ([0, 5], [0, 0]))],
    "boxes": [{"name": "crate", "center": [4.2, 1.2], "size": [0.6, 0.8], "height": 0.8}],
    "start": {"x": 1.5, "y": 1.5, "yaw": 0.0},
}
HAL_CONFIG: dict[str, Any] = {"scene": SCENE, "real_time_factor": 1.0, "odom_noise": "none"}
