"""Data types shared by the SLAM core: scans, configuration, per-scan updates and counters."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, fields

import numpy as np
from numpy.typing import NDArray

from robonix_common.geometry import PoseArray


def as_pose(p: object, name: str = "pose") -> PoseArray:
    """Validate and convert anything pose-like to a float64 (3,) array (clear error otherwise)."""
    try:
        a = np.asarray(p, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be (x, y, theta), got {p!r}") from exc
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be 3 finite numbers (x, y, theta), got {p!r}")
    return a


@dataclass
class Scan:
    """One planar lidar sweep. ``mount`` is the lidar pose in the robot base frame (x, y, yaw)."""

    ranges: NDArray[np.float32]
    angle_min: float
    angle_increment: float
    range_min: float = 0.05
    range_max: float = 12.0
    stamp: float = 0.0
    mount: tuple[float, float, float] = (0.0, 0.0, 0.0)
    frame_id: str = "laser"

    def __post_init__(self) -> None:
        self.ranges = np.asarray(self.ranges, dtype=np.float32).reshape(-1)

    @property
    def angles(self) -> NDArray[np.float64]:
        return self.angle_min + self.angle_increment * np.arange(self.ranges.size, dtype=np.float64)


@dataclass
class SlamConfig:
    """Tunables (slam_toolbox-like defaults). Validated on construction; errors name the field."""

    resolution: float = 0.05
    max_range: float = 12.0  # beams longer than this are not used (m)
    min_travel_distance: float = 0.2  # motion gating: integrate a scan after this much travel (m) ...
    min_travel_heading: float = 0.2  # ... or this much rotation (rad)
    # sequential scan-to-submap matching
    search_window_xy: float = 0.3  # half-width (m)
    search_window_theta: float = 0.2  # half-width (rad)
    angular_step: float = 0.008  # rad
    coarse_factor: int = 4  # cells per coarse cell (branch and bound level)
    smear_sigma: float = 0.075  # likelihood-field Gaussian sigma (m)
    running_buffer_size: int = 20  # nodes in the running submap
    lookup_rebuild_nodes: int = 3  # rebuild the running-submap lookup every this many nodes (EDT cost)
    min_response: float = 0.35  # below: fall back to odometry
    match_penalty: float = 0.2  # score reduction at the window edge: prior on the odometry seed
    refine: bool = True  # sub-cell Gauss-Newton refinement of the correlative optimum
    # loop closure
    loop_closure: bool = True
    loop_search_radius: float = 3.0  # candidate nodes within this distance (m)
    loop_min_chain_distance: float = 6.0  # ... and at least this far back along the path (m)
    loop_submap_radius: float = 4.0  # old nodes within this distance of the candidate form the submap
    loop_search_window_xy: float = 1.0
    loop_search_window_theta: float = 0.3
    loop_coarse_factor: int = 6
    loop_min_response: float = 0.55
    loop_max_correction: float = 1.5  # consistency: largest accepted correction (m) ...
    loop_max_correction_ratio: float = 0.15  # ... plus this fraction of the chain distance
    loop_cooldown_nodes: int = 8  # nodes between loop-closure attempts after a success
    loop_retry_nodes: int = 2  # ... and after a rejected attempt
    # loop-closure verification: a closure is added only if it is precise, never "probably right"
    loop_inlier_distance: float = 0.05  # an endpoint is an inlier within this distance of the old submap (m)
    loop_min_inlier_fraction: float = 0.8  # ... and this fraction of endpoints must be inliers (overlap test)
    loop_verify: bool = True  # reverse match: the old node's scan into the current local submap must agree
    loop_verify_xy: float = 0.03  # largest forward/reverse disagreement (m) ...
    loop_verify_theta: float = 0.015  # ... and (rad)
    loop_sigma_floor_xy: float = 0.01  # loop edges are never trusted more than this (m) ...
    loop_sigma_floor_theta: float = 0.005  # ... and (rad): conservative next to the scan-matching chain
    loop_huber: float = 3.0  # Huber kernel on loop edges in the optimiser (standard deviations); 0 = off
    loop_max_chi2: float = 16.0  # a new loop edge still this inconsistent after optimisation is removed
    optimizer_iterations: int = 15
    re_render_threshold: float = 0.02  # re-render a node's scan when it moved more than this (m, at max range)
    # occupancy grid (log-odds)
    log_odds_hit: float = 0.85
    log_odds_miss: float = -0.4
    log_odds_min: float = -2.0
    log_odds_max: float = 3.5
    occupied_threshold: float = 0.2  # log-odds above -> 100
    free_threshold: float = -0.2  # log-odds below -> 0
    grid_chunk: int = 64  # the grid grows in chunks of this many cells
    # robustness
    max_odom_jump_distance: float = 1.0  # per scan (m): larger odometry steps are treated as jumps
    max_odom_jump_heading: float = 1.0  # per scan (rad)
    odom_sigma_xy: float = 0.05  # odometry-fallback edge std dev per node (m)
    odom_sigma_theta: float = 0.03  # (rad)
    min_valid_beams: int = 20  # scans with fewer usable beams are skipped

    def __post_init__(self) -> None:
        positive = ("resolution", "max_range", "search_window_xy", "search_window_theta", "angular_step",
                    "smear_sigma", "loop_search_radius", "loop_submap_radius", "loop_search_window_xy",
                    "loop_search_window_theta", "loop_inlier_distance", "loop_verify_xy",
                    "loop_verify_theta", "loop_sigma_floor_xy", "loop_sigma_floor_theta", "log_odds_hit", "log_odds_max", "max_odom_jump_distance",
                    "max_odom_jump_heading", "odom_sigma_xy", "odom_sigma_theta")
        for f in fields(self):
            v = getattr(self, f.name)
            if isinstance(v, bool):
                continue
            if not isinstance(v, int | float) or not math.isfinite(v):
                raise ValueError(f"SlamConfig.{f.name} must be a finite number, got {v!r}")
            if f.name in positive and v <= 0:
                raise ValueError(f"SlamConfig.{f.name} must be > 0, got {v!r}")
        for name in ("min_travel_distance", "min_travel_heading", "loop_min_chain_distance",
                     "loop_max_correction", "loop_max_correction_ratio", "loop_cooldown_nodes", "loop_retry_nodes",
                     "re_render_threshold", "loop_huber", "loop_max_chi2"):
            if getattr(self, name) < 0:
                raise ValueError(f"SlamConfig.{name} must be >= 0, got {getattr(self, name)!r}")
        for name in ("coarse_factor", "loop_coarse_factor", "running_buffer_size", "lookup_rebuild_nodes", "grid_chunk",
                     "optimizer_iterations", "min_valid_beams"):
            v = getattr(self, name)
            if int(v) != v or v < 1:
                raise ValueError(f"SlamConfig.{name} must be a positive integer, got {v!r}")
            setattr(self, name, int(v))
        for name in ("min_response", "loop_min_response", "match_penalty", "loop_min_inlier_fraction"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                raise ValueError(f"SlamConfig.{name} must be in [0, 1], got {getattr(self, name)!r}")
        if self.log_odds_miss >= 0:
            raise ValueError(f"SlamConfig.log_odds_miss must be < 0, got {self.log_odds_miss!r}")
        if not self.log_odds_min < self.free_threshold <= self.occupied_threshold < self.log_odds_max:
            raise ValueError("SlamConfig.free_threshold/occupied_threshold must satisfy "
                             "log_odds_min < free_threshold <= occupied_threshold < log_odds_max")

    def to_dict(self) -> dict[str, object]:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict[str, object]) -> SlamConfig:
        """Build from a mapping; unknown keys are an error naming the key (typos must not pass silently)."""
        names = {f.name for f in fields(cls)}
        unknown = sorted(set(d) - names)
        if unknown:
            raise ValueError(f"SlamConfig: unknown field(s) {unknown}")
        return cls(**d)  # type: ignore[arg-type]


@dataclass
class SlamStats:
    """Counters; the provider exposes them so skipped input is visible, never silent."""

    scans_received: int = 0
    scans_integrated: int = 0
    scans_gated: int = 0  # skipped cheaply by motion gating
    scans_skipped_invalid: int = 0  # empty / all-invalid / too few beams
    scans_skipped_time: int = 0  # stamp not increasing
    odom_jumps: int = 0
    beams_nan: int = 0
    beams_inf: int = 0
    beams_out_of_range: int = 0
    match_failures: int = 0  # fell back to odometry
    loop_closures: int = 0
    loop_rejected: int = 0
    optimizations: int = 0
    last_warning: str = ""

    def to_dict(self) -> dict[str, object]:
        return asdict(self)


@dataclass
class Update:
    """Result of one ``SlamEngine.process`` call."""

    pose_map: PoseArray
    map_to_odom: PoseArray
    map_changed: bool
    integrated: bool
    response: float = float("nan")
    loop_closed: bool = False
    skipped_reason: str = ""
    stats: SlamStats = field(default_factory=SlamStats)
