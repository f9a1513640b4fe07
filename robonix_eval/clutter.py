"""Cluttered obstacle fields for navigation benchmarks, and a configuration-space proof that each is passable.

Worlds are made by a method unrelated to the scenes the navigation stack was tuned on: a cellular
automaton on a 0.15 m grid (random fill, a few smoothing passes) gives fields of 0.15 m posts that clump
into small clusters; walls close three sides; the robot starts below the field and its goal lies 10 m
above the start.

A world is kept only if a configuration-space search proves that the rotating rectangular footprint,
grown by a margin, can get from the start to the goal. The proof is *sound*: (x, y) is discretised at
``res`` and the heading at ``pi / bins`` (the rectangle is symmetric under a half turn), and every cell of
that (x, y, heading) grid is declared free only if the footprint grown by ``margin + r·dθ/2 + res/√2`` at
the cell's centre touches no obstacle, which covers every pose inside the cell. Cells adjacent in (x, y)
(8-neighbours, same heading bin) or in heading (same position) are connected; a connected chain of free
cells from start to goal is therefore a real collision-free motion with at least ``margin`` clearance.
The test is conservative by ``r·dθ/2 + res/√2 + res·√2/8`` per side plus the rasterisation of the
obstacles to ``res`` (measured: a barrier gap must be 0.10 m wider than body + 2·margin, i.e. about 5 cm per
side): a few barely-passable worlds are rejected, none is
wrongly kept.

Pure numpy and scipy; scenes are returned as plain dicts in the simulator's scene format.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

XY = tuple[float, float]
Rect = tuple[float, float, float, float]   # x0, y0, x1, y1 (axis-aligned)


@dataclass(frozen=True)
class ClutterSpec:
    """Geometry of one family of clutter worlds (defaults: the issue's 10 m crossing)."""

    width: float = 6.0          # m between the side walls
    field_y0: float = 2.0       # m: the post field spans field_y0..field_y1 across the whole width
    field_y1: float = 10.0
    cell: float = 0.15          # m: post size and automaton cell
    start: tuple[float, float, float] = (3.0, 1.0, math.pi / 2)
    goal: tuple[float, float, float] = (3.0, 11.0, math.pi / 2)
    wall: float = 0.15          # m wall thickness
    top: float = 12.0           # m: the world's upper bound (open side)


@dataclass(frozen=True)
class FootprintBox:
    """The robot as a centred rectangle (half-length along x, half-width along y)."""

    half_length: float = 0.35
    half_width: float = 0.25

    @property
    def circumscribed(self) -> float:
        return math.hypot(self.half_length, self.half_width)


@dataclass
class ClutterWorld:
    """One generated world: the obstacle rectangles, its scene dict, and what the proof found."""

    seed: int
    fill: float
    posts: NDArray[np.bool_]          # (rows, cols) automaton cells, row 0 at field_y0
    post_rects: list[Rect]            # the posts merged into rectangles
    wall_rects: list[Rect]
    passable: bool
    shortest: float                   # m: lower bound on the centre's path length (inf if not passable)
    spec: ClutterSpec

    def scene(self) -> dict:
        """The world in the simulator's scene format (walls as segments, posts merged into boxes)."""
        s = self.spec
        half = s.wall / 2
        walls = [
            {"start": [0.0, 0.0], "end": [s.width, 0.0], "thickness": s.wall, "height": 1.0, "name": "wall_s"},
            {"start": [0.0, 0.0], "end": [0.0, s.top], "thickness": s.wall, "height": 1.0, "name": "wall_w"},
            {"start": [s.width, 0.0], "end": [s.width, s.top], "thickness": s.wall, "height": 1.0,
             "name": "wall_e"},
        ]
        boxes = [{"center": [(x0 + x1) / 2, (y0 + y1) / 2], "size": [x1 - x0, y1 - y0], "height": 0.8,
                  "name": f"post_{i}"} for i, (x0, y0, x1, y1) in enumerate(self.post_rects)]
        return {"name": f"clutter_{self.seed}", "description": f"clutter field, fill {self.fill:.2f}",
                "bounds": [-half, -half, s.width + half, s.top], "walls": walls, "boxes": boxes,
                "start": list(s.start), "waypoints": {"goal": [s.goal[0], s.goal[1]]}}


def post_field(rng: np.random.Generator, shape: tuple[int, int], fill: float, iterations: int = 2,
               survive: int = 2) -> NDArray[np.bool_]:
    """Cellular automaton: random fill, then smoothing passes where an empty cell fills when ≥ 5 of its 8
    neighbours are occupied and an occupied one stays when ≥ ``survive`` are (lone posts and thin strands
    vanish, clumps round off, dense areas close up)."""
    from scipy.ndimage import convolve

    occ = rng.random(shape) < fill
    kernel = np.ones((3, 3), dtype=np.int16)
    kernel[1, 1] = 0
    for _ in range(iterations):
        n = convolve(occ.astype(np.int16), kernel, mode="constant", cval=0)
        occ = (n >= 5) | (occ & (n >= survive))
    return occ


def merge_rows(occ: NDArray[np.bool_]) -> list[tuple[int, int, int, int]]:
    """Occupied cells -> rectangles (row0, row1, col0, col1), half-open: horizontal runs stacked upward while
    the run repeats exactly. Keeps the simulator's geom count far below one box per post."""
    done: list[tuple[int, int, int, int]] = []
    open_runs: dict[tuple[int, int], int] = {}
    for r in range(occ.shape[0] + 1):
        runs: set[tuple[int, int]] = set()
        if r < occ.shape[0]:
            edges = np.flatnonzero(np.diff(np.concatenate(([0], occ[r].astype(np.int8), [0]))))
            runs = {(int(a), int(b)) for a, b in zip(edges[::2], edges[1::2], strict=True)}
        for run in list(open_runs):
            if run not in runs:
                done.append((open_runs.pop(run), r, run[0], run[1]))
        for run in runs:
            open_runs.setdefault(run, r)
    return done


def world_rects(posts: NDArray[np.bool_], spec: ClutterSpec) -> tuple[list[Rect], list[Rect]]:
    """Obstacle rectangles: the merged posts, and the three walls (as thick rectangles)."""
    c = spec.cell
    x_off = (spec.width - posts.shape[1] * c) / 2
    rects: list[Rect] = [(x_off + c0 * c, spec.field_y0 + r0 * c, x_off + c1 * c, spec.field_y0 + r1 * c)
                         for r0, r1, c0, c1 in merge_rows(posts)]
    h = spec.wall / 2
    walls = [(-h, -h, spec.width + h, h), (-h, -h, h, spec.top), (spec.width - h, -h, spec.width + h, spec.top)]
    return rects, walls


def rasterize(rects: list[Rect], bounds: Rect, res: float) -> NDArray[np.bool_]:
    """Cells (row 0 at the bottom) that intersect any rectangle: an over-approximation of the obstacles."""
    x0, y0, x1, y1 = bounds
    cols, rows = int(math.ceil((x1 - x0) / res)), int(math.ceil((y1 - y0) / res))
    occ = np.zeros((rows, cols), dtype=bool)
    eps = 1e-9
    for a, b, c, d in rects:
        c0, c1 = int(math.floor((a - x0) / res + eps)), int(math.ceil((c - x0) / res - eps))
        r0, r1 = int(math.floor((b - y0) / res + eps)), int(math.ceil((d - y0) / res - eps))
        occ[max(r0, 0):max(r1, 0), max(c0, 0):max(c1, 0)] = True
    return occ


def _footprint_kernel(box: FootprintBox, heading: float, grow: float, res: float) -> NDArray[np.float64]:
    """Offsets (in cells) whose cell square comes within ``grow`` of the rectangle rotated by ``heading``:
    the structuring element that turns obstacle cells into configuration-space obstacles for one heading.

    The square-to-rectangle distance is the minimum over a 5 × 5 lattice of points covering the square; no
    point of the square is farther than res·√2/8 from the lattice, which is added to ``grow`` so the
    element never misses a cell that truly comes within ``grow``."""
    reach = box.circumscribed + grow + res
    n = int(math.ceil(reach / res))
    off = np.arange(-n, n + 1) * res
    ox, oy = np.meshgrid(off, off)
    sub = (np.arange(5) - 2) * res / 4          # lattice spacing res/4 spans the square's full side
    c, s = math.cos(heading), math.sin(heading)
    dist = np.full(ox.shape, np.inf)
    for sx in sub:
        for sy in sub:
            px, py = ox + sx, oy + sy
            lx, ly = c * px + s * py, -s * px + c * py
            d = np.hypot(np.maximum(np.abs(lx) - box.half_length, 0.0), np.maximum(np.abs(ly) - box.half_width, 0.0))
            np.minimum(dist, d, out=dist)
    return (dist <= grow + res * math.sqrt(2.0) / 8).astype(np.float64)


def free_configurations(occ: NDArray[np.bool_], box: FootprintBox, margin: float, res: float,
                        bins: int) -> NDArray[np.bool_]:
    """(bins, rows, cols): True where the footprint (grown by margin and the discretisation bounds) at the
    cell centre and the bin's centre heading ``k·π/bins`` touches no occupied cell."""
    from scipy.signal import fftconvolve

    dtheta = math.pi / bins
    grow = margin + box.circumscribed * dtheta / 2 + res / math.sqrt(2.0)
    out = np.empty((bins, *occ.shape), dtype=bool)
    occ_f = occ.astype(np.float64)
    for k in range(bins):
        kern = _footprint_kernel(box, k * dtheta, grow, res)
        hit = fftconvolve(occ_f, kern, mode="same")
        out[k] = hit < 0.5
    return out


def _components(free: NDArray[np.bool_]) -> NDArray[np.int32]:
    """Label free cells connected by 8-neighbour moves within a heading bin or a bin step at one place;
    the heading axis wraps (bin 0 follows the last bin)."""
    from scipy.ndimage import label

    structure = np.zeros((3, 3, 3), dtype=bool)
    structure[1] = True               # 8-neighbours in the plane
    structure[0, 1, 1] = structure[2, 1, 1] = True
    labels, _ = label(free, structure=structure)
    # wrap: merge labels that meet across the first and last heading bins
    a, b = labels[0], labels[-1]
    pairs = {(int(x), int(y)) for x, y in zip(a[(a > 0) & (b > 0)], b[(a > 0) & (b > 0)], strict=True) if x != y}
    if pairs:
        parent = np.arange(labels.max() + 1)

        def root(i: int) -> int:
            while parent[i] != i:
                parent[i] = parent[parent[i]]
                i = int(parent[i])
            return i

        for x, y in pairs:
            rx, ry = root(x), root(y)
            if rx != ry:
                parent[max(rx, ry)] = min(rx, ry)
        flat = np.array([root(i) for i in range(len(parent))], dtype=np.int32)
        labels = flat[labels]
    return labels.astype(np.int32)


def _bin(heading: float, bins: int) -> int:
    """The heading bin whose centre (k·π/bins) is nearest, modulo the half turn."""
    return int(round((heading % math.pi) / (math.pi / bins))) % bins


def prove_passable(rects: list[Rect], spec: ClutterSpec, box: FootprintBox, margin: float, *, res: float = 0.025,
                   bins: int = 90) -> tuple[bool, float]:
    """Sound configuration-space check (see the module docstring) and a lower bound on the path length: the
    shortest 8-connected route of the centre through cells free at some heading in the connected set."""
    h = spec.wall / 2
    bounds = (-h, -h, spec.width + h, spec.top)
    occ = rasterize(rects, bounds, res)
    free = free_configurations(occ, box, margin, res, bins)
    labels = _components(free)
    rows, cols = occ.shape

    def cell(x: float, y: float) -> tuple[int, int]:
        return (min(max(int((y - bounds[1]) / res), 0), rows - 1), min(max(int((x - bounds[0]) / res), 0), cols - 1))

    sr, sc = cell(*spec.start[:2])
    gr, gc = cell(*spec.goal[:2])
    start_label = int(labels[_bin(spec.start[2], bins), sr, sc])
    if start_label == 0:
        return False, math.inf
    reach = labels == start_label
    if not reach[:, gr, gc].any():
        return False, math.inf
    return True, _shortest_length(reach.any(axis=0), (sr, sc), (gr, gc), res)


def _shortest_length(free2d: NDArray[np.bool_], start: tuple[int, int], goal: tuple[int, int], res: float) -> float:
    """Dijkstra on the 8-connected grid of cells the robot's centre can occupy (a lower bound on the feasible
    path, since a heading must also fit)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import dijkstra

    rows, cols = free2d.shape
    idx = np.arange(rows * cols).reshape(rows, cols)
    src, dst, w = [], [], []
    for dr, dc in ((0, 1), (1, 0), (1, 1), (1, -1)):
        a = free2d[max(0, -dr):rows - max(0, dr), max(0, -dc):cols - max(0, dc)]
        b = free2d[max(0, dr):rows + min(0, dr) or None, max(0, dc):cols + min(0, dc) or None]
        both = a & b
        ia = idx[max(0, -dr):rows - max(0, dr), max(0, -dc):cols - max(0, dc)][both]
        ib = idx[max(0, dr):rows + min(0, dr) or None, max(0, dc):cols + min(0, dc) or None][both]
        src.append(ia)
        dst.append(ib)
        w.append(np.full(len(ia), res * math.hypot(dr, dc)))
    s, d, ww = np.concatenate(src), np.concatenate(dst), np.concatenate(w)
    graph = coo_matrix((ww, (s, d)), shape=(rows * cols, rows * cols)).tocsr()
    dist = dijkstra(graph, directed=False, indices=int(idx[start]))
    return float(dist[idx[goal]])


def generate(seed: int, fill: float, *, spec: ClutterSpec | None = None, box: FootprintBox | None = None,
             margin: float = 0.05, iterations: int = 2, survive: int = 2) -> ClutterWorld:
    """One world from a seed and a fill ratio, with the passability proof's verdict."""
    spec = spec or ClutterSpec()
    box = box or FootprintBox()
    rng = np.random.default_rng(seed)
    shape = (int(round((spec.field_y1 - spec.field_y0) / spec.cell)), int(math.floor(spec.width / spec.cell)))
    posts = post_field(rng, shape, fill, iterations, survive)
    post_rects, wall_rects = world_rects(posts, spec)
    ok, length = prove_passable(post_rects + wall_rects, spec, box, margin)
    return ClutterWorld(seed, fill, posts, post_rects, wall_rects, ok, length, spec)
