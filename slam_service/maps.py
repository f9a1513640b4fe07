"""Saved maps on disk: ``<map_dir>/<map_id>/{map.yaml, map.pgm, session.npz, meta.json}``.

map.yaml + map.pgm are Nav2 map_server format (readable by map_server and the HAL's ``from_map``);
session.npz lets mapping continue later. A save is staged in a hidden sibling folder and swapped in by
rename, so a failed or interrupted save never leaves a half-written or mixed map behind.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from robonix_api.grid import GridMap, MapFileError, atomic_write, load_map_yaml, save_map_yaml
from slam_service.core import SessionData, SessionFileError, SlamConfig, SlamEngine, load_session

_ID = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,63}$")
MAP_YAML, MAP_PGM, SESSION, META = "map.yaml", "map.pgm", "session.npz", "meta.json"


class MapIdError(ValueError):
    """The map id is not a plain name (path separators, '..', empty, too long)."""


class MapStoreError(RuntimeError):
    """A save/load/delete failed; the message says which file and why."""


def check_id(map_id: str) -> str:
    if not _ID.match(map_id or "") or ".." in map_id:
        raise MapIdError(f"map_id: {map_id!r} is not a valid name (letters, digits, '.', '_', '-'; "
                         "no path separators or '..'; at most 64 characters)")
    return map_id


@dataclass
class LoadedMap:
    map_id: str
    grid: GridMap
    session: SessionData | None
    meta: dict[str, Any]


class MapStore:
    def __init__(self, root: str | os.PathLike[str]) -> None:
        self.root = Path(root).expanduser()

    def path(self, map_id: str) -> Path:
        return self.root / check_id(map_id)

    def save(self, map_id: str, grid: GridMap, session_writer: Any, note: str = "") -> Path:
        """Write all files into a staging folder, then swap it in. ``session_writer(path)`` or None."""
        target = self.path(map_id)
        try:
            self.root.mkdir(parents=True, exist_ok=True)
            stage = Path(tempfile.mkdtemp(dir=self.root, prefix=f".{map_id}.saving-"))
        except OSError as exc:
            raise MapStoreError(f"cannot write to map_dir {self.root}: {exc.strerror or exc}") from None
        try:
            save_map_yaml(grid, stage / MAP_YAML)
            if session_writer is not None:
                session_writer(stage / SESSION)
            meta = {"map_id": map_id, "note": note, "created": time.time(),
                    "created_iso": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "resolution": grid.resolution,
                    "width": grid.width, "height": grid.height, "origin": [grid.origin_x, grid.origin_y, grid.origin_yaw],
                    "has_session": session_writer is not None}
            atomic_write(stage / META, json.dumps(meta, indent=1).encode())
            old = None
            if target.exists():
                old = self.root / f".{map_id}.old-{os.getpid()}-{time.monotonic_ns()}"
                os.rename(target, old)
            os.rename(stage, target)
            if old is not None:
                shutil.rmtree(old, ignore_errors=True)
        except Exception as exc:
            shutil.rmtree(stage, ignore_errors=True)
            reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
            raise MapStoreError(f"cannot save map {map_id!r} to {target}: {reason}") from None
        return target

    def load(self, map_id: str, with_session: bool) -> LoadedMap:
        folder = self.path(map_id)
        if not folder.is_dir():
            raise MapStoreError(f"no map {map_id!r} in {self.root}")
        try:
            grid = load_map_yaml(folder / MAP_YAML)
        except MapFileError as exc:
            raise MapStoreError(str(exc)) from None
        session = None
        if with_session:
            if not (folder / SESSION).is_file():
                raise MapStoreError(f"{folder / SESSION}: no saved session: load map {map_id!r} in localization mode")
            try:
                session = load_session(folder / SESSION)
            except SessionFileError as exc:
                raise MapStoreError(str(exc)) from None
        return LoadedMap(map_id, grid, session, self._meta(folder))

    def _meta(self, folder: Path) -> dict[str, Any]:
        try:
            meta = json.loads((folder / META).read_text())
            return meta if isinstance(meta, dict) else {}
        except (OSError, ValueError):
            return {}

    def list(self) -> list[dict[str, Any]]:
        """One entry per map folder (hidden staging folders skipped), newest first."""
        out: list[dict[str, Any]] = []
        if not self.root.is_dir():
            return out
        for folder in self.root.iterdir():
            if folder.name.startswith(".") or not folder.is_dir() or not _ID.match(folder.name):
                continue
            meta = self._meta(folder)
            entry = {"map_id": folder.name, "path": str(folder), "note": meta.get("note", ""),
                     "created": meta.get("created"), "resolution": meta.get("resolution"),
                     "width": meta.get("width"), "height": meta.get("height"),
                     "has_session": (folder / SESSION).is_file(), "valid": (folder / MAP_YAML).is_file()}
            out.append(entry)
        return sorted(out, key=lambda e: -(e["created"] or 0.0))

    def delete(self, map_id: str) -> None:
        folder = self.path(map_id)
        if not folder.is_dir():
            raise MapStoreError(f"no map {map_id!r} in {self.root}")
        try:
            shutil.rmtree(folder)
        except OSError as exc:
            raise MapStoreError(f"cannot delete {folder}: {exc.strerror or exc}") from None


def load_engine(store: MapStore, slam_cfg: SlamConfig, map_id: str, mode: str,
                initial_pose: tuple[float, float, float] | None) -> SlamEngine:
    """A fresh engine on a saved map; MapStoreError (names the file) or ValueError when it cannot be used."""
    loaded = store.load(map_id, with_session=mode == "mapping")
    engine = SlamEngine(slam_cfg, mode)  # type: ignore[arg-type]
    engine.load(grid=loaded.grid, session=loaded.session, mode=mode, initial_pose=initial_pose)  # type: ignore[arg-type]
    return engine


# ---------------------------------------------------------------- crash autosave

AUTOSAVE_DIR = ".autosave"


class Autosave:
    """The running session's crash copy: ``<map_dir>/.autosave/<instance>/session.npz``.

    Written atomically (temp file + ``os.replace``), so a kill in the middle leaves the previous copy;
    read back when ``rbnx boot`` restarts the service after a crash (``RBNX_RESTARTS`` > 0). Hidden from
    ``list_maps`` (a dot folder) and never a saved map: ``save_map`` is still how a map is kept.
    """

    def __init__(self, map_dir: str | os.PathLike[str], instance: str) -> None:
        self.folder = Path(map_dir).expanduser() / AUTOSAVE_DIR / check_id(instance)
        self.path = self.folder / SESSION

    def write(self, session: SessionData) -> Path:
        from slam_service.core import save_session

        self.folder.mkdir(parents=True, exist_ok=True)
        return save_session(session, self.path)

    def read(self) -> SessionData | None:
        """The last autosaved session, or None when there is none or it cannot be read (logged by caller)."""
        if not self.path.is_file():
            return None
        return load_session(self.path)

    def discard(self) -> None:
        """A fresh start: an autosave of an earlier run must never be resumed by a later crash. An
        unusable map_dir is not an error here (saving reports it; the autosave thread warns)."""
        try:
            self.path.unlink(missing_ok=True)
        except OSError:
            pass


def resume_engine(session: SessionData, slam_cfg: SlamConfig) -> tuple[SlamEngine, tuple[float, float, float]]:
    """A mapping engine continuing ``session``, and map->odom at its last node (pose ∘ odom⁻¹).

    The odometry source kept running while SLAM was down, so the robot's map pose at the first scan after
    the restart is this map->odom composed with the odometry then (the caller's loop does that)."""
    from robonix_api.geometry import compose, inverse

    engine = SlamEngine(slam_cfg, "mapping")
    engine.load(session=session, mode="mapping")
    if session.graph.n_nodes:
        m2o = compose(session.graph.poses[-1], inverse(session.odom[-1]))
    else:
        m2o = engine.map_to_odom()
    return engine, (float(m2o[0]), float(m2o[1]), float(m2o[2]))
