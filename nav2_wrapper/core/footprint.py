"""Robot footprint: polygon, inscribed/circumscribed radii, and sample points for collision checks.

The polygon comes from the robot description, which ``nav2_wrapper.robot_io`` reads; the core never reads files.
"""

from __future__ import annotations

import ast
import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray


def _seg_dist(px: float, py: float, a: NDArray, b: NDArray) -> float:
    ab = b - a
    t = float(np.clip(((px - a[0]) * ab[0] + (py - a[1]) * ab[1]) / max(float(ab @ ab), 1e-12), 0.0, 1.0))
    return math.hypot(px - (a[0] + t * ab[0]), py - (a[1] + t * ab[1]))


@dataclass
class Footprint:
    """Base-frame polygon (N, 2), counter-clockwise. Radii as Nav2 computes them (about the origin)."""

    polygon: NDArray[np.float64]
    inscribed_radius: float = field(init=False)
    circumscribed_radius: float = field(init=False)

    def __post_init__(self) -> None:
        self.polygon = np.asarray(self.polygon, dtype=float).reshape(-1, 2)
        if len(self.polygon) < 3:
            raise ValueError(f"footprint needs at least 3 points, got {len(self.polygon)}")
        n = len(self.polygon)
        self.inscribed_radius = min(_seg_dist(0.0, 0.0, self.polygon[i], self.polygon[(i + 1) % n])
                                    for i in range(n))
        self.circumscribed_radius = float(np.max(np.hypot(self.polygon[:, 0], self.polygon[:, 1])))

    @classmethod
    def from_string(cls, text: str) -> Footprint:
        """Parse Nav2's footprint string form ``"[[x, y], [x, y], ...]"``."""
        try:
            pts = ast.literal_eval(text.strip())
        except (ValueError, SyntaxError) as exc:
            raise ValueError(f"footprint {text!r} is not a list of [x, y] points") from exc
        return cls(np.asarray(pts, dtype=float))

    def to_string(self) -> str:
        return "[" + ", ".join(f"[{x:g}, {y:g}]" for x, y in self.polygon) + "]"

    def padded(self, margin: float) -> Footprint:
        """The polygon grown outward by ``margin`` (each edge moved out along its normal, corners mitred), as
        Nav2's ``footprint_padding`` does; exact for the rectangle, a slight over-growth at sharp corners."""
        p = self.polygon
        area2 = float(np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1]))
        e_next = np.roll(p, -1, axis=0) - p
        normals = np.column_stack([e_next[:, 1], -e_next[:, 0]]) / np.hypot(*e_next.T)[:, None]
        if area2 < 0:          # clockwise: outward is the other side
            normals = -normals
        n_prev = np.roll(normals, 1, axis=0)
        denom = 1.0 + np.sum(normals * n_prev, axis=1)
        return Footprint(p + margin * (normals + n_prev) / np.maximum(denom, 1e-6)[:, None])

    def outline_points(self, spacing: float) -> NDArray[np.float64]:
        """Points along the polygon edges (≤ spacing apart) plus the origin: what a collision check samples."""
        pts = [np.zeros((1, 2))]
        n = len(self.polygon)
        for i in range(n):
            a, b = self.polygon[i], self.polygon[(i + 1) % n]
            k = max(1, int(math.ceil(float(np.hypot(*(b - a))) / spacing)))
            t = np.arange(k)[:, None] / k
            pts.append(a + t * (b - a))
        return np.vstack(pts)
