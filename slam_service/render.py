"""Map card image: the occupancy grid as a PNG for dashboards, with optional overlays."""

from __future__ import annotations

import io
import math

import numpy as np
from numpy.typing import ArrayLike
from PIL import Image, ImageDraw

from robonix_common.grid import GridMap

UNKNOWN_GREY = 205


def render_map_png(grid: GridMap, robot_pose: ArrayLike | None = None, footprint: ArrayLike | None = None,
                   trajectory: ArrayLike | None = None, plan: ArrayLike | None = None, *, scale: int = 1) -> bytes:
    """PNG bytes: unknown grey (205), free white, occupied black, row 0 at the bottom of the image.

    Overlays (map frame, metres): ``trajectory`` (N, 2+) blue, ``plan`` (N, 2+) green, ``robot_pose``
    (x, y, theta) red with a heading tick, ``footprint`` (K, 2) base-frame polygon drawn at the robot.
    """
    if scale < 1:
        raise ValueError(f"scale must be >= 1, got {scale}")
    d = grid.data
    pix = np.full(d.shape, UNKNOWN_GREY, dtype=np.uint8)
    pix[(d >= 0) & (d < 50)] = 255
    pix[d >= 50] = 0
    img = Image.fromarray(pix[::-1].copy(), mode="L").convert("RGB")
    if scale > 1:
        img = img.resize((img.width * scale, img.height * scale), Image.NEAREST)
    draw = ImageDraw.Draw(img)
    h = grid.height

    def to_px(pts: np.ndarray) -> list[tuple[float, float]]:
        res = grid.resolution
        c, s = math.cos(-grid.origin_yaw), math.sin(-grid.origin_yaw)
        dx, dy = pts[:, 0] - grid.origin_x, pts[:, 1] - grid.origin_y
        u = (c * dx - s * dy) / res * scale
        v = (h - (s * dx + c * dy) / res) * scale
        return list(zip(u.tolist(), v.tolist(), strict=True))

    for path, colour in ((trajectory, (40, 90, 255)), (plan, (0, 170, 0))):
        if path is not None:
            p = np.asarray(path, dtype=float).reshape(len(path), -1)[:, :2]
            if len(p) >= 2:
                draw.line(to_px(p), fill=colour, width=max(1, scale))
    if robot_pose is not None:
        x, y, th = (float(v) for v in np.asarray(robot_pose, dtype=float).reshape(3))
        if footprint is not None:
            fp = np.asarray(footprint, dtype=float).reshape(-1, 2)
            c, s = math.cos(th), math.sin(th)
            world = fp @ np.array([[c, -s], [s, c]]).T + [x, y]
            draw.polygon(to_px(world), outline=(220, 0, 0))
        (u, v), (u2, v2) = to_px(np.array([[x, y], [x + 0.3 * math.cos(th), y + 0.3 * math.sin(th)]]))
        rad = max(2.0, 0.1 / grid.resolution * scale)
        draw.ellipse([u - rad, v - rad, u + rad, v + rad], fill=(220, 0, 0))
        draw.line([(u, v), (u2, v2)], fill=(220, 0, 0), width=max(1, scale))
    buf = io.BytesIO()
    img.save(buf, format="PNG")
    return buf.getvalue()
