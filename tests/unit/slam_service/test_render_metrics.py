"""Map card PNG and the metric helpers."""

from __future__ import annotations

import io

import numpy as np
import pytest
from PIL import Image

from robonix_common.grid import GridMap
from slam_service.core import align_se2, ate_rmse, occupied_iou
from slam_service.render import render_map_png


def test_png_colours_and_orientation() -> None:
    data = np.full((4, 6), -1, dtype=np.int8)
    data[0, 0] = 100  # bottom-left cell
    data[3, 5] = 0  # top-right cell
    png = render_map_png(GridMap(data, 0.1))
    img = np.asarray(Image.open(io.BytesIO(png)).convert("L"))
    assert img.shape == (4, 6)
    assert img[3, 0] == 0  # occupied, drawn at the bottom of the image
    assert img[0, 5] == 255  # free, top right
    assert img[1, 2] == 205  # unknown grey


def test_png_overlays_and_scale() -> None:
    g = GridMap(np.zeros((40, 60), dtype=np.int8), 0.05, -1.0, -1.0)
    fp = [[0.35, 0.25], [-0.35, 0.25], [-0.35, -0.25], [0.35, -0.25]]
    png = render_map_png(g, robot_pose=(0.5, 0.0, 0.3), footprint=fp, trajectory=[[0, 0], [0.5, 0.2]],
                         plan=np.array([[0.5, 0.0, 0.0], [1.5, 0.5, 0.0]]), scale=2)
    img = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))
    assert img.shape == (80, 120, 3)
    assert (img[..., 0] > 200).sum() > 0
    assert ((img[..., 0] > 200) & (img[..., 1] < 50)).any()
    with pytest.raises(ValueError, match="scale must be >= 1"):
        render_map_png(g, scale=0)


def test_ate_alignment() -> None:
    rng = np.random.default_rng(0)
    gt = np.c_[rng.uniform(0, 5, (50, 2)), np.zeros(50)]
    th = 0.3
    rot = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
    est = np.c_[gt[:, :2] @ rot.T + [1.0, -2.0], np.zeros(50)]
    assert ate_rmse(est, gt) > 1.0
    assert ate_rmse(est, gt, align=True) < 1e-9
    assert align_se2(est, gt)[2] == pytest.approx(-th)
    with pytest.raises(ValueError, match="same non-zero length"):
        ate_rmse(est[:3], gt)


def test_iou_identity_tolerance_and_offsets() -> None:
    d = np.zeros((50, 50), dtype=np.int8)
    d[10, 5:45] = 100
    gt = GridMap(d, 0.05)
    assert occupied_iou(gt, gt, tolerance_cells=0) == 1.0
    shifted = GridMap(np.roll(d, 1, axis=0), 0.05)
    assert occupied_iou(shifted, gt, tolerance_cells=0) == 0.0
    assert occupied_iou(shifted, gt, tolerance_cells=1) == 1.0
    # a different origin/extent is resampled by cell centre
    big = GridMap(np.pad(d, 10, constant_values=-1), 0.05, -0.5, -0.5)
    assert occupied_iou(big, gt, tolerance_cells=0) == 1.0
