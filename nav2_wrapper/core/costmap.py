"""Layered 2-D costmap (static + obstacle + inflation) in Nav2 cost values, global or rolling.

Layers combine like Nav2's LayeredCostmap: the static layer overwrites, the obstacle layer uses
``updateWithMax`` (unknown in the layer never overrides; unknown in the master is overridden), and the
inflation layer inflates every lethal cell with Nav2's exponential decay. Every change recomputes only a
window around it (expanded by the inflation radius), which is what keeps a growing SLAM map cheap.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from robonix_common.geometry import Pose2D
from robonix_common.grid import GridMap
from robonix_common.params import param

from .costs import FREE, INSCRIBED, LETHAL, NO_INFORMATION, inflation_cost
from .footprint import Footprint


@dataclass
class ObservationSource:
    """One laser observation source of an obstacle layer (Nav2 names and defaults)."""

    name: str = "scan"
    topic: str = "/scan"
    marking: bool = param(True, "mark obstacles at the scan's returns")
    clearing: bool = param(True, "clear cells along each beam up to its return")
    obstacle_max_range: float = param(2.5, "returns farther than this are not marked", unit="m", gt=0)
    obstacle_min_range: float = param(0.0, "returns closer than this are not marked", unit="m", ge=0)
    raytrace_max_range: float = param(3.0, "beams clear up to this far", unit="m", gt=0)
    raytrace_min_range: float = param(0.0, "beams clear from this far out", unit="m", ge=0)
    inf_is_valid: bool = param(False, "a beam without a return (+inf) clears up to raytrace_max_range")


@dataclass
class CostmapConfig:
    """Costmap + layer parameters; names follow Nav2 where Nav2 has the parameter. The footprint comes from the
    robot description and is passed in, never read here."""

    footprint: Footprint = field(kw_only=True)
    name: str = "global_costmap"
    resolution: float = param(0.05, "cell size (a global costmap takes the static map's)", unit="m", gt=0)
    rolling_window: bool = param(False, "a window that moves with the robot (local costmap)")
    width: float = param(5.0, "size of a rolling window (or of a global costmap without a static map)", unit="m",
                         gt=0)
    height: float = param(5.0, "see width", unit="m", gt=0)
    origin_x: float = param(0.0, "origin of a fixed costmap without a static map", unit="m")
    origin_y: float = param(0.0, "see origin_x", unit="m")
    static_layer: bool = param(True, "use the static layer (its 'enabled' key)")
    obstacle_layer: bool = param(True, "use the obstacle layer (its 'enabled' key; off without an active source)")
    inflation_layer: bool = param(True, "use the inflation layer (its 'enabled' key)")
    track_unknown_space: bool = param(True, "unknown map cells stay unknown (else free); Nav2's default is false")
    lethal_cost_threshold: int = param(100, "map occupancy at or above this is lethal", ge=1, le=100)
    unknown_cost_value: int = param(-1, "map value that means unknown")
    trinary_costmap: bool = param(True, "map cells are free, lethal or unknown (no graded costs)")
    inflation_radius: float = param(0.55, "inflate lethal cells this far", unit="m", gt=0)
    cost_scaling_factor: float = param(10.0, "exponential decay of the inflated cost with distance", unit="1/m",
                                       gt=0)
    inflate_unknown: bool = param(False, "inflation also raises the cost of unknown cells")
    observation_sources: list[ObservationSource] = field(default_factory=lambda: [ObservationSource()])


@dataclass
class RangeScan:
    """The fields of a planar laser scan the obstacle layer needs (what a sensor_msgs/LaserScan carries)."""

    ranges: NDArray[np.float64]
    angle_min: float
    angle_increment: float
    range_min: float = 0.0
    range_max: float = float("inf")


def static_costs(grid: NDArray[np.int8], cfg: CostmapConfig) -> NDArray[np.uint8]:
    """Nav2 StaticLayer::interpretValue, vectorised."""
    g = np.asarray(grid)
    out = np.zeros(g.shape, dtype=np.uint8)
    unknown = g == cfg.unknown_cost_value
    lethal = (g >= cfg.lethal_cost_threshold) & ~unknown
    if not cfg.trinary_costmap:
        mid = (g > 0) & ~lethal & ~unknown
        out[mid] = np.clip(np.round(g[mid].astype(float) / cfg.lethal_cost_threshold * LETHAL), 0, INSCRIBED - 1)
    out[lethal] = LETHAL
    out[unknown] = NO_INFORMATION if cfg.track_unknown_space else FREE
    return out


class Costmap:
    """A costmap on a regular grid; ``costs`` is the master uint8 array, shape (rows, cols), row 0 at the bottom."""

    def __init__(self, cfg: CostmapConfig) -> None:
        self.cfg = cfg
        self.resolution = float(cfg.resolution)
        self._default = NO_INFORMATION if cfg.track_unknown_space else FREE
        self._map: GridMap | None = None          # last static map (rolling windows sample it)
        self._map_costs: NDArray[np.uint8] | None = None
        self.version = 0                           # bumped on every change, so users can cache
        rows = max(1, int(round(cfg.height / self.resolution)))
        cols = max(1, int(round(cfg.width / self.resolution)))
        self._alloc(cfg.origin_x, cfg.origin_y, rows, cols)

    # ---- geometry ---------------------------------------------------------------------------------
    def _alloc(self, ox: float, oy: float, rows: int, cols: int) -> None:
        self.origin_x, self.origin_y = float(ox), float(oy)
        self.static = np.full((rows, cols), self._default, dtype=np.uint8)
        self.obstacle = np.full((rows, cols), NO_INFORMATION if self.cfg.track_unknown_space else FREE,
                                dtype=np.uint8)
        self.costs = np.full((rows, cols), self._default, dtype=np.uint8)

    @property
    def shape(self) -> tuple[int, int]:
        return self.costs.shape  # type: ignore[return-value]

    def world_to_cell(self, x: NDArray | float, y: NDArray | float) -> tuple[NDArray, NDArray]:
        """World (costmap frame) → (col, row), possibly out of bounds."""
        c = np.floor((np.asarray(x, dtype=float) - self.origin_x) / self.resolution).astype(np.int64)
        r = np.floor((np.asarray(y, dtype=float) - self.origin_y) / self.resolution).astype(np.int64)
        return c, r

    def cell_to_world(self, col: NDArray | int, row: NDArray | int) -> tuple[NDArray, NDArray]:
        x = self.origin_x + (np.asarray(col, dtype=float) + 0.5) * self.resolution
        y = self.origin_y + (np.asarray(row, dtype=float) + 0.5) * self.resolution
        return x, y

    def in_bounds(self, col: NDArray | int, row: NDArray | int) -> NDArray[np.bool_]:
        col, row = np.asarray(col), np.asarray(row)
        return (col >= 0) & (col < self.shape[1]) & (row >= 0) & (row < self.shape[0])

    def cost_at(self, x: NDArray | float, y: NDArray | float, outside: int = NO_INFORMATION) -> NDArray[np.uint8]:
        """Master cost at world points; ``outside`` for points off the grid."""
        c, r = self.world_to_cell(x, y)
        ok = self.in_bounds(c, r)
        out = np.full(np.shape(c), outside, dtype=np.uint8)
        out[ok] = self.costs[r[ok], c[ok]]
        return out

    def footprint_costs(self, poses: NDArray, points: NDArray, outside: int = NO_INFORMATION) -> NDArray[np.uint8]:
        """Per pose (N, 3), the costs at the footprint sample points (N, P): the collision check's input."""
        poses = np.atleast_2d(np.asarray(poses, dtype=float))
        c, s = np.cos(poses[:, 2])[:, None], np.sin(poses[:, 2])[:, None]
        px = poses[:, 0:1] + c * points[None, :, 0] - s * points[None, :, 1]
        py = poses[:, 1:2] + s * points[None, :, 0] + c * points[None, :, 1]
        return self.cost_at(px, py, outside)

    # ---- static layer -----------------------------------------------------------------------------
    def set_static_map(self, grid: GridMap) -> None:
        """Take a new /map. Global costmaps adopt its geometry (re-framing a grown map) and recompute only
        where the static costs changed; rolling windows resample it on their next origin update."""
        if not self.cfg.static_layer:
            return
        new_costs = static_costs(grid.data, self.cfg)
        self._map, self._map_costs = grid, new_costs
        if self.cfg.rolling_window:
            self._resample_static()
            self._recompute(0, self.shape[0], 0, self.shape[1])
            return
        same = (abs(grid.resolution - self.resolution) < 1e-9 and new_costs.shape == self.shape
                and abs(grid.origin_x - self.origin_x) < 1e-9 and abs(grid.origin_y - self.origin_y) < 1e-9)
        diff = new_costs != self.static if same else (new_costs != self._reframe(grid)) | self._fresh
        self.static = new_costs
        if not diff.any():
            return
        rows = np.flatnonzero(diff.any(axis=1))
        cols = np.flatnonzero(diff.any(axis=0))
        self._recompute(int(rows[0]), int(rows[-1]) + 1, int(cols[0]), int(cols[-1]) + 1)

    def _reframe(self, grid: GridMap) -> NDArray[np.uint8]:
        """Move to the new map's geometry, keeping the old layers where the grids are cell-aligned.

        Returns the old static costs in the new frame; ``_fresh`` marks the cells nothing was kept for."""
        old_static, old_obst, old_costs = self.static, self.obstacle, self.costs
        old_ox, old_oy, old_res = self.origin_x, self.origin_y, self.resolution
        self.resolution = float(grid.resolution)
        self._alloc(grid.origin_x, grid.origin_y, grid.height, grid.width)
        dc = (old_ox - self.origin_x) / self.resolution
        dr = (old_oy - self.origin_y) / self.resolution
        aligned = abs(old_res - self.resolution) < 1e-9 and abs(dc - round(dc)) < 1e-6 and abs(dr - round(dr)) < 1e-6
        self._fresh = np.ones(self.shape, dtype=bool)
        if aligned:
            dr_i, dc_i = int(round(dr)), int(round(dc))
            for dst, src in ((self.static, old_static), (self.obstacle, old_obst), (self.costs, old_costs)):
                self._paste(dst, src, dr_i, dc_i)
            self._paste(self._fresh, np.zeros(old_static.shape, dtype=bool), dr_i, dc_i)
        self.version += 1
        return self.static

    @staticmethod
    def _paste(dst: NDArray, src: NDArray, dr: int, dc: int) -> None:
        """dst[dr + i, dc + j] = src[i, j] over the overlap."""
        r0, c0 = max(0, dr), max(0, dc)
        r1, c1 = min(dst.shape[0], dr + src.shape[0]), min(dst.shape[1], dc + src.shape[1])
        if r1 > r0 and c1 > c0:
            dst[r0:r1, c0:c1] = src[r0 - dr:r1 - dr, c0 - dc:c1 - dc]

    def _resample_static(self) -> None:
        if self._map is None or self._map_costs is None:
            return
        rows, cols = self.shape
        x, y = self.cell_to_world(np.arange(cols)[None, :], np.arange(rows)[:, None])
        mc, mr = self._map.world_to_cell(x, y)
        mc, mr = np.broadcast_arrays(mc, mr)
        ok = self._map.in_bounds(mc, mr)
        self.static = np.full((rows, cols), self._default, dtype=np.uint8)
        self.static[ok] = self._map_costs[mr[ok], mc[ok]]

    # ---- rolling window ---------------------------------------------------------------------------
    def update_origin(self, robot_x: float, robot_y: float) -> None:
        """Centre a rolling window on the robot (snapped to cells); obstacle marks move with the world."""
        if not self.cfg.rolling_window:
            return
        rows, cols = self.shape
        res = self.resolution
        ox = math.floor((robot_x - cols * res / 2.0) / res) * res
        oy = math.floor((robot_y - rows * res / 2.0) / res) * res
        dc = int(round((self.origin_x - ox) / res))
        dr = int(round((self.origin_y - oy) / res))
        if dc == 0 and dr == 0 and self.version > 0:
            return
        old = self.obstacle
        self.origin_x, self.origin_y = ox, oy
        self.obstacle = np.full_like(old, NO_INFORMATION if self.cfg.track_unknown_space else FREE)
        self._paste(self.obstacle, old, dr, dc)
        self._resample_static()
        self._recompute(0, rows, 0, cols)

    # ---- obstacle layer ---------------------------------------------------------------------------
    def update_scan(self, scan: RangeScan, sensor_pose: NDArray | Pose2D) -> None:
        """Ray-trace clearing then marking (Nav2 order) for every observation source, in the costmap frame."""
        if not self.cfg.obstacle_layer or not self.cfg.observation_sources:
            return
        sx, sy, sth = (float(v) for v in sensor_pose)
        r = np.asarray(scan.ranges, dtype=float)
        ang = scan.angle_min + scan.angle_increment * np.arange(len(r)) + sth
        reach = 0.0
        for src in self.cfg.observation_sources:
            finite = np.isfinite(r)
            valid = finite & (r >= scan.range_min) & (r <= scan.range_max)
            if src.clearing:
                dist = np.where(valid, np.minimum(r, src.raytrace_max_range), -1.0)
                if src.inf_is_valid:   # +inf (no return) clears to the raytrace range; -inf (too close) never
                    dist = np.where((r > scan.range_max) & ~np.isnan(r), src.raytrace_max_range, dist)
                self._clear_rays(sx, sy, ang, dist, src.raytrace_min_range)
                reach = max(reach, src.raytrace_max_range)
            if src.marking:
                m = valid & (r <= src.obstacle_max_range) & (r >= src.obstacle_min_range)
                c, rr = self.world_to_cell(sx + r[m] * np.cos(ang[m]), sy + r[m] * np.sin(ang[m]))
                ok = self.in_bounds(c, rr)
                self.obstacle[rr[ok], c[ok]] = LETHAL
                reach = max(reach, src.obstacle_max_range)
        c0, r0 = self.world_to_cell(sx - reach, sy - reach)
        c1, r1 = self.world_to_cell(sx + reach, sy + reach)
        self._recompute(int(r0), int(r1) + 1, int(c0), int(c1) + 1)

    def _clear_rays(self, sx: float, sy: float, ang: NDArray, dist: NDArray, dmin: float) -> None:
        step = self.resolution * 0.5
        if not np.any(dist > dmin):
            return
        t = np.arange(dmin, float(dist.max()), step)
        keep = t[None, :] < dist[:, None]
        x = sx + t[None, :] * np.cos(ang)[:, None]
        y = sy + t[None, :] * np.sin(ang)[:, None]
        c, r = self.world_to_cell(x[keep], y[keep])
        ok = self.in_bounds(c, r)
        self.obstacle[r[ok], c[ok]] = FREE

    def clear(self) -> None:
        """Nav2 ClearEntireCostmap: forget every sensor mark; the static layer stays as last received."""
        self.obstacle[:] = NO_INFORMATION if self.cfg.track_unknown_space else FREE
        self._recompute(0, self.shape[0], 0, self.shape[1])

    # ---- combination + inflation -------------------------------------------------------------------
    def _combine(self, r0: int, r1: int, c0: int, c1: int) -> NDArray[np.uint8]:
        m = (self.static[r0:r1, c0:c1].copy() if self.cfg.static_layer
             else np.full((r1 - r0, c1 - c0), self._default, dtype=np.uint8))
        if self.cfg.obstacle_layer:
            o = self.obstacle[r0:r1, c0:c1]
            upd = (o != NO_INFORMATION) & ((m == NO_INFORMATION) | (m < o))
            m[upd] = o[upd]
        return m

    def _recompute(self, r0: int, r1: int, c0: int, c1: int) -> None:
        """Layers changed in rows r0:r1, cols c0:c1: rebuild the master there plus the inflation reach around
        it, reading the layers one more inflation reach out (so distances to lethal cells stay exact)."""
        rows, cols = self.shape
        k = int(math.ceil(self.cfg.inflation_radius / self.resolution)) + 1 if self.cfg.inflation_layer else 0
        r0, r1, c0, c1 = max(0, r0 - k), min(rows, r1 + k), max(0, c0 - k), min(cols, c1 + k)
        self.version += 1
        if r1 <= r0 or c1 <= c0:
            return
        if not self.cfg.inflation_layer:
            self.costs[r0:r1, c0:c1] = self._combine(r0, r1, c0, c1)
            return
        R0, R1, C0, C1 = max(0, r0 - k), min(rows, r1 + k), max(0, c0 - k), min(cols, c1 + k)
        m = self._combine(R0, R1, C0, C1)
        lethal = m == LETHAL
        inner = (slice(r0 - R0, r1 - R0), slice(c0 - C0, c1 - C0))
        m_in = m[inner]
        if lethal.any():
            from scipy import ndimage  # with the first map, not at process start (boot time)

            dist = ndimage.distance_transform_edt(~lethal)[inner] * self.resolution
            fp = self.cfg.footprint
            cost = inflation_cost(dist, fp.inscribed_radius, self.cfg.inflation_radius, self.cfg.cost_scaling_factor)
            unknown = m_in == NO_INFORMATION
            out = np.maximum(m_in, cost)
            take = unknown & ((cost > FREE) if self.cfg.inflate_unknown else (cost >= INSCRIBED))
            out[take] = cost[take]
            m_in = out
        self.costs[r0:r1, c0:c1] = m_in
