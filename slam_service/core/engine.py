"""SlamEngine: the facade the provider drives, one ``process`` call per lidar scan.

Mapping: motion-gated nodes, each matched against a running submap of the last nodes (sequential
edge), loop closures matched against old nodes' submap, sparse optimisation, map re-rendered from the
optimised poses. Localization: the same matcher against a fixed, loaded map; no map updates.
Bad input never raises out of ``process``: the scan is skipped and a counter says why.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time
from collections import deque
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from robonix_common.geometry import PoseArray, compose, inverse, relative, transform_points
from robonix_common.grid import GridMap
from robonix_common.scan import Scan

from .background import OptimizeJob, merged_poses, remove_edge, snapshot
from .lifelong import covered
from .lookup import LookupGrid
from .matcher import MatchResult, inlier_fraction, match_scan, refine_pose, required_margin
from .motion import (
    ScanClock,
    StepWindows,
    legacy_jump,
    loop_radius,
    loop_windows,
    search_windows,
    step_times,
    suspect_step,
    unmatched_sigmas,
)
from .occupancy import LogOddsGrid
from .posegraph import EDGE_LOOP, EDGE_ODOM, EDGE_SEQUENTIAL, OptimizeResult, PoseGraph
from .preprocess import PreparedScan, ScanError, prepare_scan
from .reorder import ReorderBuffer
from .session import SessionData
from .types import SlamConfig, SlamStats, Update, as_pose

log = logging.getLogger(__name__)
TIMING_SAMPLES = 10_000  # latest optimisation / re-render durations kept (benches read them; bounded for all-day runs)
PRUNE_PER_CALL = 4  # nodes lifelong pruning examines per new node (bounds the call; it falls behind rarely)
Mode = Literal["mapping", "localization"]


class SlamEngine:
    def __init__(self, config: SlamConfig | None = None, mode: Mode = "mapping") -> None:
        self.config = config or SlamConfig()
        if mode not in ("mapping", "localization"):
            raise ValueError(f"mode must be 'mapping' or 'localization', got {mode!r}")
        self._mode: Mode = mode
        self.last_optimize: OptimizeResult | None = None
        # Timing samples for benches and status, bounded so an all-day run does not grow them with distance
        self.optimize_times: deque[float] = deque(maxlen=TIMING_SAMPLES)  # s per loop-closure optimisation
        self.rerender_times: deque[float] = deque(maxlen=TIMING_SAMPLES)  # s per re-render batch (budget or flush)
        self.rerender_batches = 0  # re-render batches so far (the deque above keeps only the latest)
        self._fixed_map: GridMap | None = None
        self._fixed_lookup: LookupGrid | None = None
        self.reset()

    # ---------------------------------------------------------------- state
    def reset(self) -> None:
        """Forget the map and trajectory (a loaded localization map is kept)."""
        c = self.config
        self._job: OptimizeJob | None = None  # a running background solve belongs to the old graph: dropped
        self.graph = PoseGraph()
        self._odom: list[PoseArray] = []
        self._stamps: list[float] = []
        self._path: list[float] = []
        self._points: list[NDArray[np.float32]] = []
        self._origins: list[NDArray[np.float64]] = []
        self._free: dict[int, NDArray[np.float32]] = {}  # node -> base-frame ends of its no-return beams (capped)
        self._prep: PreparedScan | None = None  # the scan being processed
        self._rendered: list[NDArray[np.float64]] = []  # pose each node's scan is in the grid at
        self._pending: list[int] = []  # nodes moved by an optimisation, awaiting re-render (next first)
        self.grid = LogOddsGrid(c.resolution, hit=c.log_odds_hit, miss=c.log_odds_miss, lo=c.log_odds_min,
                                  hi=c.log_odds_max, occupied_threshold=c.occupied_threshold,
                                  free_threshold=c.free_threshold, chunk=c.grid_chunk)
        self.stats = SlamStats()
        self._map_to_odom = np.zeros(3)
        self._pose = np.zeros(3)
        self._last_odom: PoseArray | None = None
        self._last_stamp: float | None = None
        self._clock = ScanClock()  # the stream's mean scan period (bursty stamps are judged against it)
        self._initial_pose: PoseArray | None = None
        self._last_match_pose: PoseArray | None = None  # localization gating reference
        self._running: LookupGrid | None = None  # running-submap lookup, reused for a few nodes
        self._running_built_at = 0
        self._last_loop_node = -10**9
        self._prune_next = 1  # first node lifelong pruning has not examined yet
        self._loop_lookup: tuple[tuple, LookupGrid] | None = None  # (submap nodes, optimisation count, window), lookup
        self._resume_from: int | None = None  # node to link the first new node to after a session load
        self._map_cache: GridMap | None = None
        self._reorder: ReorderBuffer[tuple[Scan, PoseArray]] = ReorderBuffer(c.reorder_window_s,
                                                                             c.reorder_adaptive)
        self._dup_warned = False
        self._step = StepWindows(c.search_window_xy, c.search_window_theta, False)  # this scan's windows
        self._step_motion = (0.0, 0.0, 0.0)  # (dist, rot, gap) of this scan's odometry since the last node
        self._glitch_seed: PoseArray | None = None  # "odometry glitched" seed of a suspect step
        self._drift = 0.0  # m, position std dev accrued since the last loop closure (loop candidate radius)
        self._drift_theta = 0.0  # rad, heading std dev accrued since the last loop closure (loop window)
        self._reorder_newest = -math.inf  # newest stamp offered so far
        self._loc_ref_odom: PoseArray | None = None  # odometry at the last localization match

    @property
    def mode(self) -> Mode:
        return self._mode

    def set_mode(self, mode: Mode) -> None:
        """Switch mapping <-> localization; localization uses the loaded map or the current one."""
        if mode not in ("mapping", "localization"):
            raise ValueError(f"mode must be 'mapping' or 'localization', got {mode!r}")
        self.flush()  # scans held for reordering belong to the old mode; the map catches up with the poses
        if mode == "localization" and self._fixed_lookup is None:
            if self.graph.n_nodes == 0:
                raise ValueError("localization needs a map: load one or map first")
            self._set_fixed_map(self.map())
        self._mode = mode
        self._last_match_pose = None

    def pose(self) -> PoseArray:
        return self._pose.copy()

    def map_to_odom(self) -> PoseArray:
        return self._map_to_odom.copy()

    def trajectory(self) -> NDArray[np.float64]:
        """Current (optimised) node poses, (N, 3)."""
        return self.graph.poses.copy()

    def node_stamps(self) -> NDArray[np.float64]:
        return np.asarray(self._stamps, dtype=float)

    def map(self) -> GridMap:
        if self._mode == "localization" and self._fixed_map is not None:
            return self._fixed_map
        if self._map_cache is None:
            self._map_cache = self.grid.to_gridmap()
        return self._map_cache

    def set_initial_pose(self, pose: object) -> None:
        """Map-frame pose of the robot at the next scan (localization start, or resuming a session)."""
        self._initial_pose = as_pose(pose, "initial_pose")
        self._last_match_pose = None

    # ---------------------------------------------------------------- load / save
    def load(self, grid: GridMap | None = None, session: SessionData | None = None,
             *, mode: Mode | None = None, initial_pose: object | None = None) -> None:
        """Load a map and/or a session snapshot (:func:`slam_service.session_io.load_session` reads one from a
        file). Default mode: mapping if a session is given, else localization."""
        if grid is None and session is None:
            raise ValueError("load() needs a grid, a session, or both")
        mode = mode or ("mapping" if session is not None else "localization")
        if mode not in ("mapping", "localization"):
            raise ValueError(f"mode must be 'mapping' or 'localization', got {mode!r}")
        if grid is not None and abs(grid.origin_yaw) > 1e-9:
            raise ValueError("GridMap.origin_yaw must be 0 for SLAM localization")
        self.reset()
        self._fixed_map = self._fixed_lookup = None
        if session is not None:
            self.graph = session.graph
            self._odom = [np.asarray(o, dtype=float) for o in session.odom]
            self._stamps = [float(s) for s in session.stamps]
            self._path = [float(d) for d in session.path_dist]
            self._points = list(session.points)
            self._origins = [np.asarray(o, dtype=float) for o in session.origins]
            self._free = {int(k): np.asarray(v, dtype=np.float32).reshape(-1, 2) for k, v in session.free.items()
                          if 0 <= int(k) < self.graph.n_nodes and len(v)}
            self._rerender()
            if self.graph.n_nodes:
                self._resume_from = self.graph.n_nodes - 1
                self._pose = self.graph.poses[-1].copy()
        if grid is not None:
            self._set_fixed_map(grid)
        elif mode == "localization":
            self._set_fixed_map(self.map())
        self._mode = mode
        if initial_pose is not None:
            self.set_initial_pose(initial_pose)
        elif self.graph.n_nodes:
            self.set_initial_pose(self.graph.poses[-1])

    def session(self) -> SessionData:
        """A snapshot: the graph is copied too, so a save written after the caller's lock is released stays
        consistent while later scans add nodes (they did: 'could not broadcast (72,) into (73,)')."""
        self._settle()
        g = self.graph
        graph = dataclasses.replace(g, poses=g.poses.copy(), edge_ij=list(g.edge_ij), edge_z=list(g.edge_z),
                                    edge_info=list(g.edge_info), edge_kind=list(g.edge_kind))
        return SessionData(graph, np.asarray(self._odom).reshape(-1, 3), np.asarray(self._stamps, dtype=float),
                           np.asarray(self._path, dtype=float), list(self._points),
                           np.asarray(self._origins).reshape(-1, 2), self.config, dict(self._free))

    def _set_fixed_map(self, grid: GridMap) -> None:
        c = self.config
        m = required_margin(max(c.search_window_xy, c.max_search_window_xy, c.loop_search_window_xy),
                            max(c.coarse_factor, c.loop_coarse_factor), c.smear_sigma, grid.resolution)
        pad = int(math.ceil(m / grid.resolution))
        mask = np.pad(grid.data >= 65, pad)
        self._fixed_lookup = LookupGrid.from_mask(mask, grid.resolution, grid.origin_x - pad * grid.resolution,
                                                  grid.origin_y - pad * grid.resolution, c.smear_sigma)
        # refinement points: occupied cells that touch free space (wall surfaces). Interior cells of thick
        # walls would pull the fitted lines into the wall by up to half its thickness.
        occ = grid.data >= 65
        free = (grid.data >= 0) & (grid.data < 65)
        from scipy import ndimage  # scipy loads with the first map, not at process start (boot time)

        touch = ndimage.binary_dilation(free, np.ones((3, 3), dtype=bool))
        r, col = np.nonzero(occ & touch)
        self._fixed_lookup.points = np.stack(grid.cell_to_world(col, r), axis=1)
        self._fixed_map = grid

    # ---------------------------------------------------------------- processing
    def _skip(self, reason: str, counter: str) -> Update:
        setattr(self.stats, counter, getattr(self.stats, counter) + 1)
        self.stats.last_warning = reason
        log.warning("slam: skipped scan: %s (%s=%d)", reason, counter, getattr(self.stats, counter))
        return self._update(False, False, skipped=reason)

    def _update(self, integrated: bool, changed: bool, *, response: float = float("nan"), loop: bool = False,
                skipped: str = "") -> Update:
        return Update(self._pose.copy(), self._map_to_odom.copy(), changed, integrated, response, loop, skipped,
                      dataclasses.replace(self.stats))

    def process(self, scan: Scan, odom_pose: object, stamp: float | None = None) -> Update:
        """Integrate one scan taken at odometry pose ``odom_pose`` (odom frame). Never raises on bad input.

        Scans pass a short reorder buffer (``reorder_window_s``): the returned update is that of the last
        scan released in stamp order (a held scan returns a non-integrated update); :meth:`flush` drains it."""
        self.stats.scans_received += 1
        try:
            odom = as_pose(odom_pose, "odom_pose")
        except ValueError as exc:
            return self._skip(str(exc), "scans_skipped_invalid")
        if not isinstance(scan, Scan):
            return self._skip(f"expected a Scan, got {type(scan).__name__}", "scans_skipped_invalid")
        t = float(scan.stamp if stamp is None else stamp)
        if not math.isfinite(t):
            return self._skip(f"stamp is not finite: {t}", "scans_skipped_invalid")
        verdict, due = self._reorder.push(t, (scan, odom), hash(scan.ranges.tobytes()))
        if verdict == "duplicate":
            self.stats.scans_duplicate += 1
            if not self._dup_warned:  # one warning; the counter tells the rest
                self._dup_warned = True
                log.warning("slam: skipping exact duplicate scans (stamp %s; counted in scans_duplicate)", t)
            return self._update(False, False, skipped="duplicate scan")
        if verdict == "late":
            return self._skip(f"stamp {t} older than the reorder window allows", "scans_skipped_time")
        if t < self._reorder_newest:  # accepted although a newer scan came first: sorted into place
            self.stats.scans_reordered += 1
        self._reorder_newest = max(self._reorder_newest, t)
        return self._run(due)

    def flush(self) -> Update:
        """End of input (the end of a log, before a save, a mode switch or scoring a map): process every scan
        the reorder buffer still holds, then re-draw every node still waiting for its share of the re-render
        budget, so ``map()`` matches ``trajectory()``."""
        upd = self._run(self._reorder.flush())
        self._settle()
        self._render_pending(len(self._pending))
        return upd

    def _run(self, due: list[tuple[float, tuple[Scan, PoseArray]]]) -> Update:
        upd = None
        for t, (scan, odom) in due:
            upd = self._process_one(scan, odom, t)
        return upd if upd is not None else self._update(False, False)

    def _process_one(self, scan: Scan, odom: PoseArray, t: float) -> Update:
        c = self.config
        try:
            prep = prepare_scan(scan, c.max_range)
        except ScanError as exc:
            return self._skip(str(exc), "scans_skipped_invalid")
        self.stats.beams_nan += prep.n_nan
        self.stats.beams_inf += prep.n_inf
        self.stats.beams_out_of_range += prep.n_out_of_range
        self.stats.beams_no_return += prep.n_no_return
        if len(prep.points) < c.min_valid_beams:
            return self._skip(f"only {len(prep.points)} usable beams of {scan.ranges.size}", "scans_skipped_invalid")
        raw_gap = t - self._last_stamp if self._last_stamp is not None else 0.0
        self._last_stamp = t
        rate_dt, gap = step_times(c, raw_gap, self._clock.period())
        self._clock.tick(t)
        self._glitch_seed = None
        if self._initial_pose is not None:  # (re)start: anchor map->odom so the robot is at the given pose
            self._map_to_odom = compose(self._initial_pose, inverse(odom))
            self._initial_pose = None
        elif self._last_odom is not None:
            d = relative(self._last_odom, odom)
            dist = math.hypot(d[0], d[1])
            if c.drop_odom_jumps and legacy_jump(c, dist, d[2]):
                # old behaviour (comparisons only): keep the map pose, re-anchor odometry, lose the motion
                self._map_to_odom = compose(self._pose, inverse(odom))
                self._last_odom = odom
                return self._skip(f"odometry jump of {dist:.2f} m / {d[2]:.2f} rad", "odom_jumps")
            if not c.drop_odom_jumps and suspect_step(c, dist, d[2], rate_dt):
                self.stats.odom_jumps += 1
                self._glitch_seed = compose(self._map_to_odom, self._last_odom)  # where the robot was
        self._last_odom = odom
        predicted = compose(self._map_to_odom, odom)
        self._pose = predicted
        self._set_step(odom, gap)
        if self._mode == "localization":
            return self._localize(prep.points, predicted, odom)
        self._prep = prep  # its no-return clearing is computed only if it becomes a node
        return self._map_step(prep.points, prep.origin, predicted, odom, t)

    def _set_step(self, odom: PoseArray, gap: float) -> None:
        """This scan's search windows from its odometry motion since the last node (or localization match)
        and the data gap before it."""
        c = self.config
        ref = self._ref_odom()
        if ref is None or c.drop_odom_jumps:
            self._step = StepWindows(c.search_window_xy, c.search_window_theta, False)
            self._step_motion = (0.0, 0.0, gap)
            return
        d = relative(ref, odom)
        dist = math.hypot(d[0], d[1])
        self._step_motion = (dist, abs(float(d[2])), gap)
        self._step = search_windows(c, dist, float(d[2]), gap)

    def _ref_odom(self) -> PoseArray | None:
        if self._mode == "localization":
            return self._loc_ref_odom
        if self._resume_from is not None or not self._odom:
            return None
        return self._odom[-1]

    def _moved(self, ref: PoseArray, pose: PoseArray) -> bool:
        d = relative(ref, pose)
        return math.hypot(d[0], d[1]) >= self.config.min_travel_distance or abs(d[2]) >= self.config.min_travel_heading

    def _match(self, lookup: LookupGrid, points: NDArray, seed: PoseArray, loop: bool = False,
               step: StepWindows | None = None) -> MatchResult:
        c = self.config
        if step is None:
            step = self.loop_windows() if loop else self._step
        return match_scan(lookup, points, seed, window_xy=step.xy, window_theta=step.theta,
                          angular_step=c.angular_step, coarse_factor=c.loop_coarse_factor if loop else c.coarse_factor,
                          refine=c.refine, sigma=c.smear_sigma, penalty=0.0 if loop else c.match_penalty)

    def _localize(self, points: NDArray, predicted: PoseArray, odom: PoseArray) -> Update:
        if self._fixed_lookup is None:
            return self._skip("localization mode without a map", "scans_skipped_invalid")
        if self._last_match_pose is not None and not self._moved(self._last_match_pose, predicted):
            self.stats.scans_gated += 1
            return self._update(False, False)
        m = self._seq_match(self._fixed_lookup, points, predicted)
        self._last_match_pose = predicted
        if m.response < self.config.min_response:
            self.stats.match_failures += 1
            if self._glitch_seed is not None:  # suspect step, no match either way: do not follow the glitch
                self._pose = self._glitch_seed
                self._map_to_odom = compose(self._glitch_seed, inverse(odom))
            return self._update(False, False, response=m.response)
        self._loc_ref_odom = odom
        self._pose = m.pose
        self._map_to_odom = compose(m.pose, inverse(odom))
        self._last_match_pose = m.pose
        self.stats.scans_integrated += 1
        return self._update(True, False, response=m.response)

    def _map_step(self, points: NDArray, origin: NDArray, predicted: PoseArray, odom: PoseArray, t: float) -> Update:
        c = self.config
        n = self.graph.n_nodes
        prev = self._resume_from if self._resume_from is not None else n - 1
        if n and self._resume_from is None and not self._moved(self.graph.poses[-1], predicted):
            self.stats.scans_gated += 1
            return self._update(False, self._render_pending() > 0)
        if n == 0:
            pose, cov, kind, response = predicted, None, EDGE_ODOM, float("nan")
        else:
            pose, cov, kind, response = self._match_step(points, predicted, n)
        k = self.graph.add_node(pose)
        if n:
            ref = self.graph.poses[prev]
            z = relative(ref, pose)
            if cov is None:
                info = np.diag([1 / c.odom_sigma_xy**2, 1 / c.odom_sigma_xy**2, 1 / c.odom_sigma_theta**2])
            else:
                info = _info_in_frame(cov, ref[2])
            self.graph.add_edge(prev, k, z, info, kind)
        dist = 0.0 if n == 0 else float(np.hypot(*(pose[:2] - self.graph.poses[prev][:2])))
        if n and kind == EDGE_ODOM:  # unmatched: its whole uncertainty adds to the drift
            self._drift += math.sqrt(cov[0, 0]) if cov is not None else c.odom_sigma_xy
            self._drift_theta += math.sqrt(cov[2, 2]) if cov is not None else c.odom_sigma_theta
        else:
            self._drift += c.loop_drift_per_m * dist
            self._drift_theta += c.loop_drift_theta_per_m * dist
        self._path.append((self._path[prev] if n else 0.0) + dist)
        self._odom.append(odom)
        self._stamps.append(t)
        self._points.append(np.asarray(points, dtype=np.float32))
        self._origins.append(np.asarray(origin, dtype=float))
        if self._prep is not None:
            ends = self._prep.free_ends(c.no_return_clear_range)
            if len(ends):
                self._free[k] = ends
        self._resume_from = None
        self._render_node(k, pose)
        self._pose = pose.copy()
        self._map_to_odom = compose(pose, inverse(odom))
        loop = False
        if self._job is not None:
            if k + 1 - self._job.n_nodes >= c.optimize_apply_nodes:
                loop = self._apply_job()
        elif c.loop_closure and k - self._last_loop_node >= c.loop_cooldown_nodes:
            loop = self._try_loop_closure(k)
        if loop:
            self._drift = self._drift_theta = 0.0
        if not loop:  # a closing call already did the optimisation: its share of re-rendering starts next call
            self._render_pending()
        self._prune(k)
        self.stats.scans_integrated += 1
        return self._update(True, True, response=response, loop=loop)

    # ---------------------------------------------------------------- lifelong pruning
    def _prune(self, k: int) -> None:
        """Remove the nodes that just left the recent chain (at least ``loop_min_chain_distance`` back along
        the path and outside the running submap) when an older node already covers their place (see
        :mod:`.lifelong`): sequential matching and loop closure still see every node they use, and a
        pass through mapped rooms leaves no nodes behind. At most ``PRUNE_PER_CALL`` checks per call."""
        c = self.config
        if not c.prune_nodes or self._job is not None:  # a background solve holds node numbers: no renumbering
            return
        path = np.asarray(self._path)
        recent = np.flatnonzero(path[k] - path < c.loop_min_chain_distance)
        protect_from = min(k - c.running_buffer_size, int(recent[0]) if len(recent) else k)
        j = max(self._prune_next, 1)
        for _ in range(PRUNE_PER_CALL):
            if j >= protect_from:
                break
            if not covered(c, self.graph.poses, path, self._points, j):
                j += 1
                continue
            self._remove_node(j)  # the next node moves down into j
            path = np.delete(path, j)
            protect_from -= 1
        self._prune_next = j

    def _remove_node(self, m: int) -> None:
        """Forget node ``m``: its scan leaves the grid (exact: the grid stores sums), its edges are
        reconnected through a neighbour, and every per-node list and index shifts down past it."""
        if m < len(self._rendered):
            old = self._rendered[m]
            self.grid.integrate(transform_points(old, self._origins[m][None])[0],
                                transform_points(old, self._points[m]), weight=-1.0)
            if m in self._free:
                self._clear_free(m, old, -1.0)
            del self._rendered[m]
        self.graph.remove_node(m)
        for lst in (self._odom, self._stamps, self._path, self._points, self._origins):
            del lst[m]
        self._free = {(i - 1 if i > m else i): v for i, v in self._free.items() if i != m}
        self._pending = [i - 1 if i > m else i for i in self._pending if i != m]
        self.stats.map_nodes_pending = len(self._pending)

        def shift(i: int) -> int:
            return i - 1 if i > m else i

        self._last_loop_node, self._prune_next = shift(self._last_loop_node), shift(self._prune_next)
        self._running_built_at = shift(self._running_built_at)
        if self._loop_lookup is not None:  # keyed by node numbers: renumber, or drop if it drew m
            (nodes, *rest), lookup = self._loop_lookup
            self._loop_lookup = None if m in nodes else ((tuple(shift(i) for i in nodes), *rest), lookup)
        self._map_cache = None
        self.stats.nodes_pruned += 1

    def _match_step(self, points: NDArray, predicted: PoseArray,
                    n: int) -> tuple[PoseArray, NDArray | None, int, float]:
        """Match a scan that passed gating against the running submap (or, after an unusual step, a one-off
        wide lookup): the new node's pose, its covariance (None: odometry's), the edge kind and the response.
        An unusual step that cannot be matched is never dropped: it keeps its odometry (or, for a glitch,
        "did not move") with a large covariance."""
        c = self.config
        unusual = self._step.wide or self._glitch_seed is not None
        if unusual:  # a one-off lookup big enough for the widened windows and both seeds
            lookup = self._build_wide(predicted, points)
            self._running = None
        else:
            if (self._running is None or self._resume_from is not None
                    or n - self._running_built_at >= c.lookup_rebuild_nodes):
                self._running = self._build_running(predicted, points)
                self._running_built_at = n
            lookup = self._running
        m = self._seq_match(lookup, points, predicted)
        if m.response >= c.min_response:
            return m.pose, m.covariance, EDGE_SEQUENTIAL, m.response
        self.stats.match_failures += 1
        if not unusual:
            return predicted, None, EDGE_ODOM, m.response
        self.stats.unmatched_steps += 1
        pose = self._glitch_seed if self._glitch_seed is not None else predicted
        sxy, sth = unmatched_sigmas(c, *self._step_motion)
        return pose, np.diag([sxy**2, sxy**2, sth**2]), EDGE_ODOM, m.response

    def _seq_match(self, lookup: LookupGrid, points: NDArray, predicted: PoseArray) -> MatchResult:
        """Sequential match at the odometry prediction with this scan's (possibly widened) windows; for a
        suspect step also at "the robot did not move" (normal windows): the better response wins."""
        if self._step.wide:
            self.stats.wide_searches += 1
        m = self._match(lookup, points, predicted)
        if self._glitch_seed is not None:
            c = self.config
            alt = self._match(lookup, points, self._glitch_seed,
                              step=StepWindows(c.search_window_xy, c.search_window_theta, False))
            if alt.response > m.response:
                self.stats.odom_glitches += 1
                return alt
        return m

    def _build_wide(self, predicted: PoseArray, points: NDArray) -> LookupGrid:
        """Running-submap lookup for a wide or suspect step: centred on the robot, covering every heading
        and both seeds, with the margin the widened window needs."""
        c = self.config
        n = self.graph.n_nodes
        nodes = range(max(0, n - c.running_buffer_size), n)
        margin = required_margin(self._step.xy, c.coarse_factor, c.smear_sigma, c.resolution)
        seeds = [predicted[:2]] + ([self._glitch_seed[:2]] if self._glitch_seed is not None else [])
        centre = np.mean(seeds, axis=0)
        spread = max(float(np.hypot(*(p - centre))) for p in seeds)
        reach = float(np.max(np.hypot(points[:, 0], points[:, 1])))
        return LookupGrid.from_points(self._node_points_map(nodes), c.resolution, c.smear_sigma, margin,
                                      center=centre, half_extent=reach + spread + self._step.xy + 0.3)

    def _node_points_map(self, nodes: NDArray | list[int]) -> NDArray:
        poses = self.graph.poses
        parts = [transform_points(poses[i], self._points[i]) for i in nodes]
        return np.concatenate(parts) if parts else np.zeros((0, 2))

    def _build_running(self, center: PoseArray, points: NDArray) -> LookupGrid:
        """Lookup over the last nodes' scans, cropped to where the current scan can land (EDT cost)."""
        c = self.config
        n = self.graph.n_nodes
        if self._resume_from is not None:  # after a session load: nearest nodes in space, not in the chain
            d = np.hypot(*(self.graph.poses[:, :2] - center[:2]).T)
            nodes = np.argsort(d)[:c.running_buffer_size]
        else:
            nodes = range(max(0, n - c.running_buffer_size), n)
        margin = required_margin(c.search_window_xy, c.coarse_factor, c.smear_sigma, c.resolution)
        cur = transform_points(center, points)
        lo, hi = cur.min(axis=0), cur.max(axis=0)
        # reused for lookup_rebuild_nodes nodes: leave room for the robot to move meanwhile
        reach = float(np.max(np.hypot(*(cur - center[:2]).T))) * c.search_window_theta
        reach += c.lookup_rebuild_nodes * max(c.min_travel_distance, 0.1)
        return LookupGrid.from_points(self._node_points_map(nodes), c.resolution, c.smear_sigma, margin,
                                      center=0.5 * (lo + hi),
                                      half_extent=float(np.max(hi - lo)) / 2 + c.search_window_xy + reach + 0.2)

    def _try_loop_closure(self, k: int) -> bool:
        c = self.config
        poses = self.graph.poses
        path = np.asarray(self._path)
        old = np.flatnonzero(path[k] - path[:k] >= c.loop_min_chain_distance)
        if len(old) == 0:
            return False
        d = np.hypot(*(poses[old, :2] - poses[k, :2]).T)
        radius = loop_radius(c, self._drift)
        win = self.loop_windows()
        near = old[d <= radius]
        if len(near) == 0:
            return False
        cand = int(near[np.argmin(d[d <= radius])])
        sub = old[np.hypot(*(poses[old, :2] - poses[cand, :2]).T) <= c.loop_submap_radius]
        key = (tuple(int(i) for i in sub), self.stats.optimizations, win.xy)
        if self._loop_lookup is None or self._loop_lookup[0] != key:
            # consecutive attempts usually see the same old submap: build its field (EDT) once
            margin = required_margin(win.xy, c.loop_coarse_factor, c.smear_sigma, c.resolution)
            self._loop_lookup = (key, LookupGrid.from_points(self._node_points_map(sub), c.resolution,
                                                             c.smear_sigma, margin))
        lookup = self._loop_lookup[1]
        pts = self._points[k]
        # the wide correlative search only has to land in the right cell: half the beams suffice (the
        # refinement and the verification below use all of them)
        m = self._match(lookup, pts[::2] if len(pts) > 180 else pts, poses[k], loop=True, step=win)
        corr = float(np.hypot(*(m.pose[:2] - poses[k, :2])))
        limit = c.loop_max_correction + c.loop_max_correction_ratio * (path[k] - path[cand])
        at_edge = (abs(m.pose[0] - poses[k, 0]) > win.xy - c.resolution
                   or abs(m.pose[1] - poses[k, 1]) > win.xy - c.resolution
                   or abs(math.remainder(m.pose[2] - poses[k, 2], 2 * math.pi)) > win.theta - c.angular_step)
        if m.response < c.loop_min_response or corr > limit or at_edge:
            return self._reject_loop("response/window")
        found = self._verified_loop(lookup, k, cand, m)
        if found is None:
            return False
        pose, cov = found
        self.graph.add_edge(cand, k, relative(poses[cand], pose), _info_in_frame(cov, poses[cand][2]), EDGE_LOOP)
        if c.optimize_in_background:  # solved off the scan path, applied optimize_apply_nodes nodes later
            self._job = OptimizeJob(snapshot(self.graph), k, self.graph.n_edges - 1, c.optimizer_iterations,
                                    c.loop_huber or None, c.loop_max_chi2)
            self._job.start()
            self._last_loop_node = k
            return False
        saved = self.graph.poses.copy()
        t0 = time.perf_counter()
        res = self.graph.optimize(c.optimizer_iterations, huber=c.loop_huber or None)
        elapsed = time.perf_counter() - t0
        chi2 = float(self.graph.edge_chi2()[-1])
        if chi2 > c.loop_max_chi2:  # the rest of the graph disagrees with it: drop it, undo the optimisation
            self.graph.remove_last_edge()
            self.graph.poses = saved
            log.debug("slam: loop %d->%d removed after optimisation (chi2 %.1f)", cand, k, chi2)
            return self._reject_loop("inconsistent after optimisation")
        self.stats.loop_closures += 1
        self._last_loop_node = k
        self._optimize((res, elapsed))
        return True

    def _settle(self) -> bool:
        """Wait for and apply a pending background solve (before a save, a flush, a mode switch)."""
        return self._apply_job() if self._job is not None else False

    def _apply_job(self) -> bool:
        """Apply the background solve: its poses (later nodes carried rigidly), or, if the new loop edge is
        still inconsistent after it, drop that edge and keep the poses. Returns whether the loop was kept."""
        job, self._job = self._job, None
        assert job is not None
        job.wait()
        if job.result is None:  # the solve raised (logged by the thread): keep the chain as it is
            remove_edge(self.graph, job.edge)
            return self._reject_loop("optimisation failed")
        if not job.accepted:
            remove_edge(self.graph, job.edge)
            log.debug("slam: loop at node %d removed after optimisation (chi2 %.1f)", job.node, job.chi2)
            return self._reject_loop("inconsistent after optimisation")
        self.graph.poses = merged_poses(self.graph.poses, job.graph.poses)
        self.stats.loop_closures += 1
        self._last_loop_node = job.node  # the next attempt may follow at once: the cooldown ran meanwhile
        self._optimize((job.result, job.seconds))
        return True

    def loop_windows(self) -> StepWindows:
        """The loop match's current search windows: wider after steps the scans could not pin down."""
        return loop_windows(self.config, self._drift, self._drift_theta)

    def _reject_loop(self, why: str) -> bool:
        self.stats.loop_rejected += 1
        # retry a few nodes later, not at every node: the search is the costliest step of the pipeline
        self._last_loop_node = max(self._last_loop_node, self.graph.n_nodes - 1 - self.config.loop_cooldown_nodes
                                   + self.config.loop_retry_nodes)
        log.debug("slam: loop closure rejected: %s", why)
        return False

    def _verified_loop(self, lookup: LookupGrid, k: int, cand: int, m: MatchResult
                       ) -> tuple[NDArray, NDArray] | None:
        """Precise pose of node ``k`` against the old submap and an honest covariance, or None.

        A loop edge is far stronger evidence than one sequential edge, so it must be right to within the
        chain's own accuracy. Three checks, each cheap next to the correlative search: (1) re-fit with
        more point-to-line rounds; (2) most endpoints must land on old obstacles (the views overlap,
        not just "score well"); (3) the reverse match (the old node's scan into the *current* local
        submap) must imply the same relative pose. The covariance is floored: never tighter than
        ``loop_sigma_floor_*`` in any direction.
        """
        c = self.config
        pts = self._points[k]
        pose, cov = refine_pose(lookup, pts, m.pose, max_shift=2.0 * c.resolution, max_rot=2.0 * c.angular_step,
                                sigma=c.smear_sigma)
        if cov is None or not np.all(np.isfinite(cov)):
            self._reject_loop("refinement failed")
            return None
        if inlier_fraction(lookup, pts, pose, c.loop_inlier_distance) < c.loop_min_inlier_fraction:
            self._reject_loop("overlap")
            return None
        if c.loop_verify and not self._reverse_agrees(k, cand, pose):
            self._reject_loop("reverse match")
            return None
        cov = 0.5 * (cov + cov.T)
        floor = np.array([c.loop_sigma_floor_xy, c.loop_sigma_floor_xy, c.loop_sigma_floor_theta]) ** 2
        ev, evec = np.linalg.eigh(cov[:2, :2])  # floor the translational ellipse in every direction
        cov[:2, :2] = evec @ np.diag(np.maximum(ev, floor[0])) @ evec.T
        cov[2, 2] = max(cov[2, 2], floor[2])
        return pose, cov

    def _reverse_agrees(self, k: int, cand: int, pose_k: NDArray) -> bool:
        """Match the candidate's scan into a submap of the nodes just before ``k``, seeded where the
        forward match puts it; both directions must give the same relative pose."""
        c = self.config
        poses = self.graph.poses
        z = relative(pose_k, poses[cand])  # candidate in the frame of node k, per the forward match
        seed = compose(poses[k], z)
        nodes = range(max(0, k - c.running_buffer_size), k + 1)
        cur = transform_points(seed, self._points[cand])
        lo, hi = cur.min(axis=0), cur.max(axis=0)
        wxy, wth = 2 * c.loop_verify_xy, 2 * c.loop_verify_theta
        margin = required_margin(wxy, c.coarse_factor, c.smear_sigma, c.resolution)
        local = LookupGrid.from_points(self._node_points_map(nodes), c.resolution, c.smear_sigma, margin,
                                       center=0.5 * (lo + hi), half_extent=float(np.max(hi - lo)) / 2 + wxy + 0.2)
        r = match_scan(local, self._points[cand], seed, window_xy=wxy, window_theta=wth,
                       angular_step=c.angular_step, coarse_factor=c.coarse_factor, refine=False,
                       sigma=c.smear_sigma, penalty=0.0)
        back, _ = refine_pose(local, self._points[cand], r.pose, max_shift=2.0 * c.resolution,
                              max_rot=2.0 * c.angular_step, sigma=c.smear_sigma)
        if inlier_fraction(local, self._points[cand], back, c.loop_inlier_distance) < c.loop_min_inlier_fraction:
            return False
        d = relative(seed, back)
        return bool(math.hypot(d[0], d[1]) <= c.loop_verify_xy and abs(d[2]) <= c.loop_verify_theta)

    def _optimize(self, done: tuple[OptimizeResult, float] | None = None) -> None:
        """Optimise (unless ``done`` = (result, seconds) says it just was) and re-render the nodes that moved."""
        if done is None:
            t0 = time.perf_counter()
            res = self.graph.optimize(self.config.optimizer_iterations, huber=self.config.loop_huber or None)
            done = (res, time.perf_counter() - t0)
        res = done[0]
        self.optimize_times.append(done[1])
        self.last_optimize = res
        self.stats.optimizations += 1
        k = self.graph.n_nodes - 1
        self._pose = self.graph.poses[k].copy()
        self._map_to_odom = compose(self._pose, inverse(self._odom[k]))
        self._schedule_rerender()
        self._running = None

    def optimize(self) -> OptimizeResult | None:
        """Run a full optimisation now (e.g. before saving) and bring the map up to date; None without a graph."""
        self._settle()
        if self.graph.n_edges == 0:
            return None
        self._optimize()
        self._render_pending(len(self._pending))
        return self.last_optimize

    def _render_node(self, k: int, pose: NDArray) -> None:
        org, pts = self._origins[k], self._points[k]
        old = None
        if k < len(self._rendered):
            old = self._rendered[k]
            self.grid.integrate(transform_points(old, org[None])[0], transform_points(old, pts), weight=-1.0)
            self._rendered[k] = pose.copy()
        else:
            self._rendered.append(pose.copy())
        self.grid.integrate(transform_points(pose, org[None])[0], transform_points(pose, pts))
        if k in self._free:  # no-return beams clear free space; moved with the scan like its hits
            if old is not None:
                self._clear_free(k, old, -1.0)
            self._clear_free(k, pose, 1.0)
        self._map_cache = None

    def _clear_free(self, k: int, pose: NDArray, weight: float) -> None:
        org = transform_points(pose, self._origins[k][None])[0]
        self.grid.integrate_free(org, transform_points(pose, self._free[k]), transform_points(pose, self._points[k]),
                                 weight=weight)

    def _rerender(self) -> int:
        """Render every node from scratch at its current pose (after a session load). Returns how many."""
        self.grid.clear()
        self._rendered = []
        self._pending = []
        for k, pose in enumerate(self.graph.poses):
            self._render_node(k, pose)
        self.stats.map_nodes_pending = 0
        return self.graph.n_nodes

    def _schedule_rerender(self) -> None:
        """After an optimisation: queue the nodes whose drawn pose is off by more than ``re_render_threshold``
        (at max range), the largest shift first, so the map converges where it is most wrong.

        Nothing is drawn here: re-drawing hundreds of scans in the call that closed the loop stalled the
        scan path for up to seconds. ``_render_pending`` draws a fixed number per ``process`` call instead;
        a node count (not a time budget) keeps the result a function of the input sequence alone.
        """
        self._pending = []
        if self._rendered:
            mv = _render_shift(np.asarray(self._rendered), self.graph.poses[:len(self._rendered)],
                               self.config.max_range)
            moved = np.flatnonzero(mv > self.config.re_render_threshold)
            self._pending = [int(k) for k in moved[np.argsort(-mv[moved], kind="stable")]][::-1]
        self.stats.map_nodes_pending = len(self._pending)

    def _render_pending(self, budget: int | None = None) -> int:
        """Re-draw up to ``budget`` (default ``rerender_nodes_per_scan``) queued nodes at their current pose.
        Their old contribution is subtracted first (the grid stores exact sums). Returns how many."""
        if not self._pending:
            return 0
        n = min(len(self._pending), self.config.rerender_nodes_per_scan if budget is None else budget)
        t0 = time.perf_counter()
        for _ in range(n):
            k = self._pending.pop()  # the list is stored largest shift last
            self._render_node(k, self.graph.poses[k])
        self.rerender_times.append(time.perf_counter() - t0)
        self.rerender_batches += 1
        self.stats.map_nodes_rerendered += n
        self.stats.map_nodes_pending = len(self._pending)
        return n


def _render_shift(old: NDArray, new: NDArray, max_range: float) -> NDArray:
    """How far each node's drawn scan is off (m): the larger of its translation and its heading change
    times ``max_range`` (the shift of its farthest endpoint from the turn alone)."""
    dth = np.abs(np.remainder(new[:, 2] - old[:, 2] + math.pi, 2 * math.pi) - math.pi)
    return np.maximum(np.hypot(*(new[:, :2] - old[:, :2]).T), dth * max_range)


def _info_in_frame(cov_map: NDArray, theta: float) -> NDArray:
    """Map-frame covariance -> information matrix in the frame of a node with heading ``theta``."""
    cs, sn = math.cos(theta), math.sin(theta)
    r = np.array([[cs, sn, 0.0], [-sn, cs, 0.0], [0.0, 0.0, 1.0]])
    cov = r @ cov_map @ r.T
    return np.linalg.inv(0.5 * (cov + cov.T))
