"""Session files: a :class:`~slam_service.core.session.SessionData` snapshot on disk and back.

One ``.npz`` (no pickle, so a hostile file cannot run code) with a format tag and a version; written to
a temp file and renamed, so a crash or a full disk never leaves a half-written session behind.

The no-return clearing of each node (``free_*`` arrays) is optional in the file: a session written before
it was saved still loads (its map then lacks that clearing), and the version stays 1 so such a file is
still readable by a build that does not know the arrays (it ignores them).
"""

from __future__ import annotations

import io
import json
import os
import zipfile
from pathlib import Path

import numpy as np

from robonix_api.mapfile import atomic_write
from slam_service.core.posegraph import PoseGraph
from slam_service.core.session import SessionData
from slam_service.core.types import SlamConfig

FORMAT = "robonix-slam-session"
VERSION = 1


class SessionFileError(ValueError):
    """A session file is missing, unreadable or malformed; the message names the file and the problem."""


class SessionSaveError(OSError):
    """A session could not be written (the previous file, if any, is left untouched)."""


def save_session(data: SessionData, path: str | os.PathLike[str]) -> Path:
    """Write ``data`` atomically to ``path``; :class:`SessionSaveError` if it cannot be written."""
    path = Path(path)
    g = data.graph
    n = g.n_nodes
    offsets = np.zeros(n + 1, dtype=np.int64)
    offsets[1:] = np.cumsum([len(p) for p in data.points]) if n else []
    arrays = {
        **_free_arrays(data.free),
        "format": np.array(FORMAT),
        "version": np.array(VERSION),
        "config": np.array(json.dumps(data.config.to_dict())),
        "poses": g.poses.astype(np.float64).reshape(-1, 3),
        "odom": np.asarray(data.odom, dtype=np.float64).reshape(-1, 3),
        "stamps": np.asarray(data.stamps, dtype=np.float64).reshape(-1),
        "path_dist": np.asarray(data.path_dist, dtype=np.float64).reshape(-1),
        "points": (np.concatenate(data.points).astype(np.float32) if n else np.zeros((0, 2), np.float32)),
        "point_offsets": offsets,
        "origins": np.asarray(data.origins, dtype=np.float64).reshape(-1, 2),
        "edge_ij": np.asarray(g.edge_ij, dtype=np.int64).reshape(-1, 2),
        "edge_z": np.asarray(g.edge_z, dtype=np.float64).reshape(-1, 3),
        "edge_info": np.asarray(g.edge_info, dtype=np.float64).reshape(-1, 3, 3),
        "edge_kind": np.asarray(g.edge_kind, dtype=np.int64).reshape(-1),
    }
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    try:
        if not path.parent.is_dir():
            raise FileNotFoundError(f"directory {path.parent} does not exist")
        atomic_write(path, buf.getvalue())
    except OSError as exc:
        raise SessionSaveError(f"cannot write SLAM session to {path}: {exc}") from exc
    return path


def _free_arrays(free: dict[int, np.ndarray]) -> dict[str, np.ndarray]:
    """Per-node no-return free-stretch ends, packed like the points: node ids, offsets, concatenated ends."""
    nodes = sorted(int(k) for k, v in free.items() if len(v))
    ends = [np.asarray(free[k], dtype=np.float32).reshape(-1, 2) for k in nodes]
    offsets = np.zeros(len(nodes) + 1, dtype=np.int64)
    offsets[1:] = np.cumsum([len(e) for e in ends]) if nodes else []
    return {"free_nodes": np.asarray(nodes, dtype=np.int64),
            "free_ends": np.concatenate(ends) if nodes else np.zeros((0, 2), np.float32),
            "free_offsets": offsets}


def _read_free(a: dict[str, np.ndarray], n: int) -> dict[int, np.ndarray] | str:
    """The per-node free-stretch ends (empty for a file written without them), or what is wrong with them."""
    if "free_nodes" not in a:
        return {}
    nodes, off, ends = a["free_nodes"], a.get("free_offsets"), a.get("free_ends")
    if off is None or ends is None:
        return "'free_nodes' without 'free_offsets'/'free_ends'"
    if nodes.ndim != 1 or off.shape != (len(nodes) + 1,) or ends.ndim != 2 or ends.shape[1] != 2:
        return "'free_*' arrays have inconsistent shapes"
    if off[0] != 0 or off[-1] != len(ends) or np.any(np.diff(off) < 0):
        return "'free_offsets' are inconsistent"
    if len(nodes) and (nodes.min() < 0 or nodes.max() >= n or len(np.unique(nodes)) != len(nodes)):
        return "'free_nodes' names a node that does not exist (or one twice)"
    if not np.all(np.isfinite(ends)):
        return "'free_ends' contains NaN/inf"
    return {int(k): ends[off[i]:off[i + 1]].astype(np.float32) for i, k in enumerate(nodes)}


NEEDED = ("config", "poses", "odom", "stamps", "path_dist", "points", "point_offsets", "origins", "edge_ij",
          "edge_z", "edge_info", "edge_kind")


def _read_arrays(path: Path) -> dict[str, np.ndarray]:
    """Every array of the file, after the format tag and version are checked."""
    try:
        with np.load(path, allow_pickle=False) as z:
            a = {k: z[k] for k in z.files}
    except FileNotFoundError as exc:
        raise SessionFileError(f"{path}: no such file") from exc
    except (OSError, ValueError, zipfile.BadZipFile, EOFError) as exc:
        raise SessionFileError(f"{path}: not a SLAM session file ({type(exc).__name__}: {exc})") from exc
    if str(a.get("format", "")) != FORMAT:
        raise SessionFileError(f"{path}: not a SLAM session file (format tag {str(a.get('format', 'missing'))!r})")
    try:
        version = int(a["version"])
    except (KeyError, ValueError, TypeError) as exc:
        raise SessionFileError(f"{path}: missing or bad 'version'") from exc
    if version != VERSION:
        raise SessionFileError(f"{path}: unsupported session version {version} (this build reads {VERSION})")
    for k in NEEDED:
        if k not in a:
            raise SessionFileError(f"{path}: missing array '{k}'")
    return a


def _shape_problem(a: dict[str, np.ndarray]) -> str | None:
    """What is inconsistent between the arrays (shapes, point offsets, non-finite values), or None."""
    n, e = len(a["poses"]), len(a["edge_ij"])
    shapes = {"poses": (n, 3), "odom": (n, 3), "stamps": (n,), "path_dist": (n,), "origins": (n, 2),
              "point_offsets": (n + 1,), "edge_ij": (e, 2), "edge_z": (e, 3), "edge_info": (e, 3, 3),
              "edge_kind": (e,)}
    for k, shp in shapes.items():
        if a[k].shape != shp:
            return f"'{k}' has shape {a[k].shape}, expected {shp}"
    off, pts = a["point_offsets"], a["points"]
    if pts.ndim != 2 or pts.shape[1] != 2 or off[0] != 0 or off[-1] != len(pts) or np.any(np.diff(off) < 0):
        return "'points'/'point_offsets' are inconsistent"
    for k in ("poses", "odom", "points", "edge_z", "edge_info", "origins"):
        if not np.all(np.isfinite(a[k])):
            return f"'{k}' contains NaN/inf"
    return None


def load_session(path: str | os.PathLike[str]) -> SessionData:
    """Read and check a session file; :class:`SessionFileError` names the file and the problem."""
    path = Path(path)
    a = _read_arrays(path)
    try:
        config = SlamConfig.from_dict(json.loads(str(a["config"])))
    except (ValueError, TypeError) as exc:
        raise SessionFileError(f"{path}: bad 'config': {exc}") from exc
    problem = _shape_problem(a)
    if problem:
        raise SessionFileError(f"{path}: {problem}")
    free = _read_free(a, len(a["poses"]))
    if isinstance(free, str):
        raise SessionFileError(f"{path}: {free}")
    graph = PoseGraph(a["poses"].astype(np.float64).copy())
    try:
        for (i, j), zz, info, kind in zip(a["edge_ij"], a["edge_z"], a["edge_info"], a["edge_kind"], strict=True):
            graph.add_edge(int(i), int(j), zz, info, int(kind))
    except ValueError as exc:
        raise SessionFileError(f"{path}: bad edge: {exc}") from exc
    off, pts = a["point_offsets"], a["points"]
    points = [pts[off[k]:off[k + 1]].astype(np.float32) for k in range(len(a["poses"]))]
    return SessionData(graph, a["odom"].astype(np.float64), a["stamps"].astype(np.float64),
                       a["path_dist"].astype(np.float64), points, a["origins"].astype(np.float64), config, free)
