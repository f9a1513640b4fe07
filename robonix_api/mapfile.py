"""Nav2 map_server files (PGM + YAML) for :class:`robonix_common.grid.GridMap`.

Map files follow map_server: the PGM's first row is the top of the map, so rows are flipped on I/O.
"""

from __future__ import annotations

import math
import os
import tempfile
from pathlib import Path

import numpy as np
import yaml

from robonix_api.safefile import UnsafeFileError, read_capped
from robonix_common.grid import FREE, OCCUPIED, UNKNOWN, GridMap


class MapFileError(ValueError):
    """A map YAML/PGM is malformed; the message names the file and the key."""


#: A map YAML is a few lines; an image at most this many pixels (5000 x 5000, 250 m square at 5 cm)
#: is decoded: Pillow reads the size from the header, so a decompression bomb is refused before decoding.
YAML_MAX_BYTES = 64 * 1024
MAX_PIXELS = 25_000_000
#: Cell sizes outside this range are not a map (1e-300 m overflows every cell computation).
RESOLUTION_MIN, RESOLUTION_MAX = 1e-3, 100.0
#: |origin| beyond this (metres) is not a place a robot is.
ORIGIN_MAX = 1e6


def _number(path: Path, key: str, value: object) -> float:
    if isinstance(value, bool):
        raise MapFileError(f"{path}: {key}: must be a number, got {value!r}")
    try:
        out = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise MapFileError(f"{path}: {key}: must be a number, got {str(value)[:40]!r}") from None
    if not math.isfinite(out):
        raise MapFileError(f"{path}: {key}: must be a finite number, got {out}")
    return out


def _meta_numbers(path: Path, meta: dict) -> tuple[float, list[float], float, float, int]:
    """resolution, origin, occupied/free thresholds, negate: each finite and in range, else MapFileError."""
    res = _number(path, "resolution", meta["resolution"])
    if not RESOLUTION_MIN <= res <= RESOLUTION_MAX:
        raise MapFileError(f"{path}: resolution: must be {RESOLUTION_MIN:g}..{RESOLUTION_MAX:g} m per cell, "
                           f"got {res:g}")
    raw_origin = meta["origin"]
    if not isinstance(raw_origin, list | tuple) or len(raw_origin) != 3:
        raise MapFileError(f"{path}: origin: must be [x, y, yaw]")
    origin = [_number(path, f"origin[{i}]", v) for i, v in enumerate(raw_origin)]
    if max(abs(origin[0]), abs(origin[1])) > ORIGIN_MAX:
        raise MapFileError(f"{path}: origin: x and y must be within +-{ORIGIN_MAX:g} m")
    occ_th = _number(path, "occupied_thresh", meta.get("occupied_thresh", 0.65))
    free_th = _number(path, "free_thresh", meta.get("free_thresh", 0.25))
    if not 0.0 <= free_th < occ_th <= 1.0:
        raise MapFileError(f"{path}: free_thresh/occupied_thresh: need 0 <= free_thresh < occupied_thresh <= 1")
    negate = meta.get("negate", 0)
    if negate not in (0, 1, True, False):
        raise MapFileError(f"{path}: negate: must be 0 or 1, got {str(negate)[:40]!r}")
    return res, origin, occ_th, free_th, int(negate)


def _image_path(path: Path, image: object, image_root: Path | None) -> Path:
    if not isinstance(image, str) or not image.strip():
        raise MapFileError(f"{path}: image: must be a file name")
    img_path = Path(image)
    if not img_path.is_absolute():
        img_path = path.parent / img_path
    if image_root is not None:
        real, root = img_path.resolve(), image_root.resolve()
        if not real.is_relative_to(root):
            raise MapFileError(f"{path}: image: {image[:200]} resolves to {real}, outside the map folder {root}")
    return img_path


def load_map_yaml(path: str | os.PathLike[str], image_root: str | os.PathLike[str] | None = None) -> GridMap:
    """Read a map_server YAML + its image (PGM or anything Pillow reads) into a GridMap.

    Untrusted input: the YAML is read only as a regular file of at most :data:`YAML_MAX_BYTES`; every
    number must be finite and in range; with ``image_root`` the image must resolve inside that folder;
    an image of more than :data:`MAX_PIXELS` is refused from its header, before decoding. Every problem
    is a MapFileError naming the file and the key.
    """
    from PIL import Image, UnidentifiedImageError

    path = Path(path)
    try:
        meta = yaml.safe_load(read_capped(path, YAML_MAX_BYTES, "map YAML"))
    except UnsafeFileError as exc:
        raise MapFileError(f"{path}: {exc}") from None
    except yaml.YAMLError as exc:
        raise MapFileError(f"{path}: cannot read map YAML: {exc}") from exc
    if not isinstance(meta, dict):
        raise MapFileError(f"{path}: map YAML must be a mapping")
    for key in ("image", "resolution", "origin"):
        if key not in meta:
            raise MapFileError(f"{path}: missing key '{key}'")
    res, origin, occ_th, free_th, negate = _meta_numbers(path, meta)
    mode = str(meta.get("mode", "trinary"))
    if mode not in ("trinary", "scale", "raw"):
        raise MapFileError(f"{path}: mode: must be trinary, scale or raw, got {mode[:40]!r}")
    img_path = _image_path(path, meta["image"], Path(image_root) if image_root is not None else None)
    if not img_path.is_file():
        raise MapFileError(f"{path}: image: cannot read image {img_path}: no such regular file")
    try:
        with Image.open(img_path) as im:
            w, h = im.size  # from the header: nothing decoded yet
            if w <= 0 or h <= 0 or w * h > MAX_PIXELS:
                raise MapFileError(f"{path}: image: {img_path.name} is {w}x{h} pixels, more than the "
                                   f"{MAX_PIXELS} allowed (or empty)")
            pix = np.asarray(im.convert("L"), dtype=np.float64)
    except (OSError, UnidentifiedImageError, Image.DecompressionBombError, ValueError, SyntaxError) as exc:
        if isinstance(exc, MapFileError):
            raise
        raise MapFileError(f"{path}: image: cannot read image {img_path}: {exc}") from exc
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
