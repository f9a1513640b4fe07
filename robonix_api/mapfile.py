"""Nav2 map_server files (PGM + YAML) for :class:`robonix_common.grid.GridMap`.

Map files follow map_server: the PGM's first row is the top of the map, so rows are flipped on I/O.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numpy as np
import yaml

from robonix_common.grid import FREE, OCCUPIED, UNKNOWN, GridMap


class MapFileError(ValueError):
    """A map YAML/PGM is malformed; the message names the file and the key."""


def load_map_yaml(path: str | os.PathLike[str]) -> GridMap:
    """Read a map_server YAML + its image (PGM or anything Pillow reads) into a GridMap."""
    from PIL import Image, UnidentifiedImageError

    path = Path(path)
    try:
        meta = yaml.safe_load(path.read_text())
    except (OSError, yaml.YAMLError) as exc:
        raise MapFileError(f"{path}: cannot read map YAML: {exc}") from exc
    if not isinstance(meta, dict):
        raise MapFileError(f"{path}: map YAML must be a mapping")
    for key in ("image", "resolution", "origin"):
        if key not in meta:
            raise MapFileError(f"{path}: missing key '{key}'")
    try:
        res = float(meta["resolution"])
        origin = [float(v) for v in meta["origin"]]
        occ_th = float(meta.get("occupied_thresh", 0.65))
        free_th = float(meta.get("free_thresh", 0.25))
        negate = int(meta.get("negate", 0))
    except (TypeError, ValueError) as exc:
        raise MapFileError(f"{path}: bad number in resolution/origin/thresholds: {exc}") from exc
    if len(origin) != 3:
        raise MapFileError(f"{path}: 'origin' must be [x, y, yaw]")
    mode = str(meta.get("mode", "trinary"))
    if mode not in ("trinary", "scale", "raw"):
        raise MapFileError(f"{path}: 'mode' must be trinary, scale or raw, got {mode!r}")
    img_path = Path(meta["image"])
    if not img_path.is_absolute():
        img_path = path.parent / img_path
    try:
        with Image.open(img_path) as im:
            pix = np.asarray(im.convert("L"), dtype=np.float64)
    except (OSError, UnidentifiedImageError) as exc:
        raise MapFileError(f"{path}: cannot read image {img_path}: {exc}") from exc
    pix = pix[::-1]  # image row 0 is the top of the map
    if mode == "raw":
        data = np.where(pix > 100, UNKNOWN, pix).astype(np.int8)
    else:
        p = pix / 255.0 if negate else (255.0 - pix) / 255.0
        data = np.full(p.shape, UNKNOWN, dtype=np.int8)
        data[p > occ_th] = OCCUPIED
        data[p < free_th] = FREE
        if mode == "scale":
            mid = (p >= free_th) & (p <= occ_th)
            data[mid] = np.round(99 * (p[mid] - free_th) / (occ_th - free_th)).astype(np.int8)
    try:
        return GridMap(data, res, origin[0], origin[1], origin[2])
    except ValueError as exc:
        raise MapFileError(f"{path}: {exc}") from exc


def atomic_write(path: Path, payload: bytes) -> None:
    """Write via a temp file + rename so a crash never leaves a half-written map."""
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(payload)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def save_map_yaml(grid: GridMap, yaml_path: str | os.PathLike[str], *, occupied_thresh: float = 0.65,
                  free_thresh: float = 0.196) -> Path:
    """Write ``<name>.pgm`` + ``<name>.yaml`` (trinary, map_server readable), each atomically.

    free_thresh defaults to ROS map_saver's 0.196 so that unknown (pixel 205, p=0.196) reads back unknown.
    """
    yaml_path = Path(yaml_path)
    yaml_path.parent.mkdir(parents=True, exist_ok=True)
    pgm_path = yaml_path.with_suffix(".pgm")
    d = grid.data[::-1]
    pix = np.full(d.shape, 205, dtype=np.uint8)  # unknown
    pix[(d >= 0) & (d <= free_thresh * 100)] = 254
    pix[d >= occupied_thresh * 100] = 0
    header = f"P5\n# robonix map\n{grid.width} {grid.height}\n255\n".encode()
    atomic_write(pgm_path, header + pix.tobytes())
    meta = {
        "image": pgm_path.name,
        "mode": "trinary",
        "resolution": float(grid.resolution),
        "origin": [float(grid.origin_x), float(grid.origin_y), float(grid.origin_yaw)],
        "negate": 0,
        "occupied_thresh": occupied_thresh,
        "free_thresh": free_thresh,
    }
    atomic_write(yaml_path, yaml.safe_dump(meta, sort_keys=False).encode())
    return yaml_path
