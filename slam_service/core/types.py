"""Data types shared by the SLAM core: scans, configuration, per-scan updates and counters."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, fields

import numpy as np

from robonix_common.geometry import PoseArray
from robonix_common.params import ParamError, check_ranges, param


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
class SlamConfig:
    """Tunables (slam_toolbox-like defaults). Each field's default, range and doc are declared here once
    (:func:`robonix_common.params.param`); the ranges are physical: values past them pass the algorithm but
    would exhaust memory or CPU (a 1e-9 m resolution, a 1e6 m search window). Validated on construction;
    errors (:class:`~robonix_common.params.ParamError`) name the field."""

    resolution: float = param(0.05, ge=0.005, le=1.0, doc="m per map cell")
    max_range: float = param(12.0, ge=0.1, le=100.0, doc="m; longer beams are not used")
    min_travel_distance: float = param(0.2, ge=0, doc="m of travel after which a scan is integrated (motion gating)")
    min_travel_heading: float = param(0.2, ge=0, doc="rad of rotation after which a scan is integrated")
    # sequential scan-to-submap matching
    search_window_xy: float = param(0.3, gt=0, le=5.0, doc="m, half-width of the sequential search window")
    search_window_theta: float = param(0.2, gt=0, le=math.pi, doc="rad, half-width of the sequential search")
    angular_step: float = param(0.008, ge=0.0005, le=0.5, doc="rad between tried headings")
    coarse_factor: int = param(4, ge=1, le=64, doc="cells per coarse cell (branch and bound level)")
    smear_sigma: float = param(0.075, gt=0, le=5.0, doc="m, likelihood-field Gaussian sigma")
    running_buffer_size: int = param(20, ge=1, le=1000, doc="nodes in the running submap")
    lookup_rebuild_nodes: int = param(3, ge=1, le=1000, doc="rebuild the running-submap lookup every this many "
                                      "nodes (distance-transform cost)")
    min_response: float = param(0.35, ge=0, le=1, doc="match score below which the scan falls back to odometry")
    match_penalty: float = param(0.2, ge=0, le=1, doc="score reduction at the window edge: prior on the odometry "
                                 "seed")
    refine: bool = param(True, doc="sub-cell Gauss-Newton refinement of the correlative optimum")
    # loop closure
    loop_closure: bool = param(True, doc="search for and add loop closures")
    loop_search_radius: float = param(3.0, gt=0, le=100.0, doc="m; candidate nodes within this distance")
    loop_min_chain_distance: float = param(6.0, ge=0, doc="m; ... and at least this far back along the path")
    loop_submap_radius: float = param(4.0, gt=0, le=100.0, doc="m; old nodes within this distance of the "
                                      "candidate form the submap")
    loop_search_window_xy: float = param(1.0, gt=0, le=10.0, doc="m, half-width of the loop search window")
    loop_search_window_theta: float = param(0.3, gt=0, le=math.pi, doc="rad, half-width of the loop search")
    loop_coarse_factor: int = param(6, ge=1, le=64, doc="cells per coarse cell in loop matching")
    loop_min_response: float = param(0.55, ge=0, le=1, doc="loop match score needed to consider a closure")
    loop_max_correction: float = param(1.5, ge=0, doc="m; largest accepted loop correction ...")
    loop_max_correction_ratio: float = param(0.15, ge=0, doc="... plus this fraction of the chain distance")
    loop_cooldown_nodes: int = param(8, ge=0, le=100_000, doc="nodes between loop attempts after a success")
    loop_retry_nodes: int = param(2, ge=0, le=100_000, doc="nodes between loop attempts after a rejection")
    # loop-closure verification: a closure is added only if it is precise, never "probably right"
    loop_inlier_distance: float = param(0.05, gt=0, doc="m; an endpoint within this of the old submap is an "
                                        "inlier")
    loop_min_inlier_fraction: float = param(0.8, ge=0, le=1, doc="fraction of endpoints that must be inliers "
                                            "(overlap test)")
    loop_verify: bool = param(True, doc="reverse match: the old node's scan into the current local submap must "
                              "agree")
    loop_verify_xy: float = param(0.03, gt=0, doc="m; largest forward/reverse disagreement ...")
    loop_verify_theta: float = param(0.015, gt=0, doc="rad; ... and in heading")
    loop_sigma_floor_xy: float = param(0.01, gt=0, doc="m; loop edges are never trusted more than this ...")
    loop_sigma_floor_theta: float = param(0.005, gt=0, doc="rad; ... and this (conservative next to the chain)")
    loop_huber: float = param(3.0, ge=0, doc="Huber kernel on loop edges (standard deviations); 0 = off")
    loop_max_chi2: float = param(16.0, ge=0, doc="a new loop edge still this inconsistent after optimisation "
                                 "is removed")
    optimizer_iterations: int = param(15, ge=1, le=1000, doc="Gauss-Newton iterations per optimisation")
    optimize_in_background: bool = param(False, doc="a loop closure's optimisation runs on a worker thread, off the "
                                         "scan path; its result is applied optimize_apply_nodes nodes later. Off by "
                                         "default: applying 4 nodes late made loop closure harmful on the hard "
                                         "simulated apartment (ATE 0.058 vs 0.036 m without, seed 2)")
    optimize_apply_nodes: int = param(4, ge=1, le=10_000, doc="nodes after a loop closure at which its background "
                                      "optimisation is applied (waited for there if still running: the result "
                                      "depends on the input alone, never on the machine's speed)")
    re_render_threshold: float = param(0.02, ge=0, doc="m at max range; re-render a node's scan when it moved "
                                       "more")
    rerender_nodes_per_scan: int = param(12, ge=1, le=1_000_000, doc="nodes moved by an optimisation are "
                                         "re-rendered at most this many per process() call (bounds the call)")
    # occupancy grid (log-odds)
    log_odds_hit: float = param(0.85, gt=0, doc="log-odds added per hit")
    log_odds_miss: float = param(-0.4, lt=0, doc="log-odds added per miss")
    log_odds_min: float = param(-2.0, doc="clamp of the reported log-odds (below free_threshold)")
    log_odds_max: float = param(3.5, gt=0, doc="clamp of the reported log-odds (above occupied_threshold)")
    occupied_threshold: float = param(0.2, doc="log-odds above -> 100")
    free_threshold: float = param(-0.2, doc="log-odds below -> 0")
    grid_chunk: int = param(64, ge=8, le=4096, doc="cells; the grid grows in chunks of this many")
    # robustness: large or uncertain odometry steps widen the search instead of being dropped
    wide_step_distance: float = param(0.5, gt=0, doc="m of odometry travel since the last node beyond which the "
                                      "sequential search windows widen")
    wide_step_heading: float = param(0.5, gt=0, doc="rad of odometry rotation since the last node beyond which "
                                     "the windows widen")
    wide_step_gap_s: float = param(0.5, gt=0, doc="s without scans beyond which the windows widen (the odometry "
                                   "step is less certain)")
    window_growth: float = param(0.2, ge=0, le=2.0, doc="window half-width added per m travelled (xy) and per rad "
                             "turned (theta) in a wide step")
    window_growth_gap: float = param(0.05, ge=0, le=2.0, doc="m and rad added to the windows per s of data gap")
    max_search_window_xy: float = param(1.0, gt=0, le=5.0, doc="m; widened xy window is bounded by this")
    max_search_window_theta: float = param(0.8, gt=0, le=math.pi, doc="rad; widened heading window is bounded "
                                           "by this")
    max_odom_rate_distance: float = param(2.0, gt=0, doc="m/s; a faster odometry step between two scans is "
                                          "suspect: the 'odometry glitched, robot did not move' seed is tried too")
    max_odom_rate_heading: float = param(3.0, gt=0, doc="rad/s; a faster odometry turn between scans is suspect")
    unmatched_sigma_growth: float = param(0.2, ge=0, le=2.0, doc="m per m and rad per rad of step: std dev added to "
                                          "the odometry edge of a wide step that could not be matched")
    drop_odom_jumps: bool = param(False, doc="old behaviour, for comparisons only: steps beyond max_odom_jump_* "
                                  "drop the scan and discard the motion")
    max_odom_jump_distance: float = param(1.0, gt=0, doc="m per scan; with drop_odom_jumps, larger steps are dropped")
    max_odom_jump_heading: float = param(1.0, gt=0, doc="rad per scan; with drop_odom_jumps, larger turns are "
                                         "dropped")
    loop_search_radius_max: float = param(10.0, gt=0, le=100.0, doc="m; the loop candidate radius grows with the "
                                          "pose uncertainty since the last loop closure up to this")
    loop_search_window_xy_max: float = param(3.0, gt=0, le=10.0, doc="m; the loop search window half-width grows "
                                             "by 3 sigma of the position uncertainty since the last loop closure "
                                             "up to this")
    loop_search_window_theta_max: float = param(0.8, gt=0, le=math.pi, doc="rad; the loop search heading "
                                                "half-width grows by 3 sigma of the heading uncertainty since the "
                                                "last loop closure up to this")
    loop_drift_per_m: float = param(0.0, ge=0, le=1.0, doc="m of position std dev accrued per m of matched travel "
                                    "(3 sigma widens the loop candidate radius); 0: only unmatched steps widen it "
                                    "(1 % cost 0.4 cm ATE on the hard sim loop: more, weaker candidates)")
    loop_drift_theta_per_m: float = param(0.0, ge=0, le=1.0, doc="rad of heading std dev accrued per m of matched "
                                          "travel (3 sigma widens the loop search's heading window): a small "
                                          "heading error per match adds up over a long loop")
    no_return_clear_range: float = param(3.0, ge=0, le=100.0, doc="m; beams with no return (the range_max "
                                         "sentinel or +inf) clear free space this far, never a hit; 0 = off")
    # lifelong mapping: nodes bounded by the mapped area, not the distance driven
    prune_nodes: bool = param(True, doc="a node whose place an older node already covers is removed once it leaves "
                              "the recent chain (its chain reconnected), so the graph, the node scans and the session "
                              "stay proportional to the mapped area")
    prune_distance: float = param(0.3, gt=0, le=5.0, doc="m; an older node this close to a node covers it ...")
    prune_heading: float = param(0.5, gt=0, le=math.pi, doc="rad; ... if also facing within this")
    prune_min_overlap: float = param(0.7, ge=0, le=1, doc="... and this fraction of its scan endpoints lies within "
                                     "prune_overlap_distance of the older scan's")
    prune_overlap_distance: float = param(0.1, gt=0, le=1.0, doc="m; endpoint distance counted as overlap")
    prune_min_covering: int = param(2, ge=1, le=100, doc="passes whose older nodes must cover a place before a newer "
                                    "node there is dropped: the map keeps this many views of each place and heading")
    # stamps
    reorder_window_s: float = param(1.0, ge=0, le=5.0, doc="s; scans up to this late are sorted into stamp order "
                                    "(output delayed by at most this); later ones are skipped")
    reorder_adaptive: bool = param(True, doc="hold scans for the window only once the stream has delivered a late "
                                   "scan: in-order streams keep zero latency")
    odom_sigma_xy: float = param(0.05, gt=0, doc="m; odometry-fallback edge std dev per node")
    odom_sigma_theta: float = param(0.03, gt=0, doc="rad; odometry-fallback edge std dev per node")
    min_valid_beams: int = param(20, ge=1, le=100_000, doc="scans with fewer usable beams are skipped")

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if isinstance(v, bool):
                continue
            if not isinstance(v, int | float) or not math.isfinite(v):
                raise ParamError(f.name, f"must be a finite number, got {v!r}", "SlamConfig.")
            if f.type == "int":
                if int(v) != v:
                    raise ParamError(f.name, f"must be an integer, got {v!r}", "SlamConfig.")
                setattr(self, f.name, int(v))
        check_ranges(self, "SlamConfig.")
        if not self.log_odds_min < self.free_threshold <= self.occupied_threshold < self.log_odds_max:
            raise ParamError("free_threshold", "free_threshold/occupied_threshold must satisfy "
                             "log_odds_min < free_threshold <= occupied_threshold < log_odds_max", "SlamConfig.")

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
    scans_skipped_time: int = 0  # stamp later than the reorder window allows
    scans_reordered: int = 0  # arrived late, sorted into stamp order by the reorder buffer
    scans_duplicate: int = 0  # exact duplicates (same stamp, same ranges), skipped
    odom_jumps: int = 0  # odometry steps faster than max_odom_rate_* (or, with drop_odom_jumps, dropped scans)
    wide_searches: int = 0  # scans matched with windows widened for a large step or a data gap
    odom_glitches: int = 0  # suspect steps where "the robot did not move" matched better than the odometry
    unmatched_steps: int = 0  # wide steps added with their odometry and a large covariance
    beams_nan: int = 0
    beams_inf: int = 0
    beams_out_of_range: int = 0
    beams_no_return: int = 0  # readings >= the scan's range_max (the no-return sentinel) or +inf
    match_failures: int = 0  # fell back to odometry
    loop_closures: int = 0
    loop_rejected: int = 0
    nodes_pruned: int = 0  # nodes removed because an older node covers the same place (lifelong mapping)
    optimizations: int = 0
    last_warning: str = ""
    map_nodes_rerendered: int = 0  # node scans re-drawn at their optimised pose (spread over calls)
    map_nodes_pending: int = 0  # moved nodes not yet re-drawn: the published map lags the graph by these

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
