"""Saved maps on disk: ``<map_dir>/<map_id>/{map.yaml, map.pgm, session.npz, meta.json, .robonix-map}``.

map.yaml + map.pgm are Nav2 map_server format (readable by map_server and the HAL's ``from_map``);
session.npz lets mapping continue later. A save is staged in a hidden sibling folder and swapped in by
rename, so a failed or interrupted save never leaves a half-written or mixed map behind. Saves of one id
are serialized (a lock per id in this process, ``flock`` on the map_dir across processes for the swap).
``map_dir`` must lie under the maps root, and only folders holding the store's marker are replaced or
deleted (:mod:`slam_service.map_paths`).
"""

from __future__ import annotations

import fcntl
import json
import logging
import os
import shutil
import tempfile
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from robonix_api.mapfile import MapFileError, atomic_write, load_map_yaml, save_map_yaml
from robonix_common.grid import GridMap
from slam_service.core import SessionData, SlamConfig, SlamEngine
from slam_service.map_paths import (
    MARKER,
    NOTE_MAX,
    MapDirError,
    MapIdError,
    check_id,
    check_note,
    is_map_folder,
    resolve_map_dir,
    stale_staging,
)
from slam_service.session_io import SessionFileError, load_session

log = logging.getLogger("slam_service.maps")
MAP_YAML, MAP_PGM, SESSION, META = "map.yaml", "map.pgm", "session.npz", "meta.json"
LOCK_FILE = ".robonix-maps.lock"
#: list() stops at this many maps or this many bytes of JSON, well below gRPC's 4 MB message limit.
LIST_MAX_ENTRIES = 1000
LIST_MAX_BYTES = 1 << 20
#: meta.json larger than this is not read (a hand-written or legacy file must not blow up list_maps).
META_MAX_BYTES = 64 * 1024

__all__ = ["Autosave", "LoadedMap", "MapDirError", "MapIdError", "MapInvalidError", "MapStore", "MapStoreError",
           "check_id", "load_engine",
           "resume_engine"]


class MapStoreError(RuntimeError):
    """A save/load/delete failed; the message says which file and why."""


class MapInvalidError(MapStoreError):
    """A saved map's files are not a usable map (bad YAML value, image outside its folder, too large):
    the caller's argument is at fault, answered INVALID_ARGUMENT naming the file and the key."""


_id_locks: dict[tuple[str, str], threading.Lock] = {}
_id_locks_guard = threading.Lock()


def _id_lock(root: Path, map_id: str) -> threading.Lock:
    with _id_locks_guard:
        return _id_locks.setdefault((str(root), map_id), threading.Lock())


@dataclass
class LoadedMap:
    map_id: str
    grid: GridMap
    session: SessionData | None
    meta: dict[str, Any]


class MapStore:
    """The saved maps in one folder under the maps root.

    ``MapStore(map_dir)`` resolves ``map_dir`` against the maps root (``maps_root``, default
    :func:`~slam_service.map_paths.default_maps_root`) and raises MapDirError naming ``map_dir`` when it
    lies outside; then it cleans staging folders that a killed save left behind.
    """

    def __init__(self, map_dir: str | os.PathLike[str], maps_root: str | os.PathLike[str] | None = None) -> None:
        self.root = resolve_map_dir(map_dir, maps_root)
        self._maps_root = maps_root
        self.cleaned = self.clean_staging()

    def path(self, map_id: str) -> Path:
        return self.root / check_id(map_id)

    def _check_root(self) -> None:
        """The folder must still resolve to itself (no symlink swapped in since INIT)."""
        try:
            again = resolve_map_dir(self.root, self._maps_root)
        except MapDirError as exc:
            raise MapStoreError(str(exc)) from None
        if again != self.root:
            raise MapStoreError(f"map_dir {self.root} now resolves to {again}; send CMD_INIT again")

    @contextmanager
    def _swap_lock(self) -> Iterator[None]:
        """Exclusive across processes for the rename swap (and the staging cleanup)."""
        fd = os.open(self.root / LOCK_FILE, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX)
            yield
        finally:
            os.close(fd)  # releases the lock

    def clean_staging(self) -> int:
        """Remove staging folders of saves whose process is gone; an interrupted swap (the old map moved
        aside, the new one not yet in) gets its old map back. Returns how many folders were handled."""
        if not self.root.is_dir():
            return 0
        n = 0
        try:
            with self._swap_lock():
                for path, map_id, kind in stale_staging(self.root):
                    target = self.root / map_id
                    if kind == "old" and not target.exists() and not target.is_symlink():
                        os.rename(path, target)
                        log.warning("restored map %r from %s (a save was interrupted)", map_id, path.name)
                    else:
                        shutil.rmtree(path, ignore_errors=True)
                    n += 1
        except OSError as exc:
            log.warning("cannot clean staging folders in %s: %s", self.root, exc.strerror or exc)
        if n:
            log.info("cleaned %d staging folder(s) left by interrupted saves in %s", n, self.root)
        return n

    def save(self, map_id: str, grid: GridMap, session_writer: Any, note: str = "") -> Path:
        """Write all files into a staging folder, then swap it in. ``session_writer(path)`` or None."""
        target = self.path(map_id)
        try:
            check_note(note)
        except ValueError as exc:
            raise MapStoreError(str(exc)) from None
        with _id_lock(self.root, map_id):
            return self._save_locked(map_id, target, grid, session_writer, note)

    def _save_locked(self, map_id: str, target: Path, grid: GridMap, session_writer: Any, note: str) -> Path:
        try:
            self.root.mkdir(parents=True, exist_ok=True)
            self._check_root()
            stage = Path(tempfile.mkdtemp(dir=self.root, prefix=f".{map_id}.saving-{os.getpid()}-"))
        except OSError as exc:
            raise MapStoreError(f"cannot write to map_dir {self.root}: {exc.strerror or exc}") from None
        try:
            save_map_yaml(grid, stage / MAP_YAML)
            if session_writer is not None:
                session_writer(stage / SESSION)
            meta = {"map_id": map_id, "note": note, "created": time.time(),
                    "created_iso": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "resolution": grid.resolution,
                    "width": grid.width, "height": grid.height,
                    "origin": [grid.origin_x, grid.origin_y, grid.origin_yaw],
                    "has_session": session_writer is not None}
            atomic_write(stage / META, json.dumps(meta, indent=1).encode())
            atomic_write(stage / MARKER,
                         b"written by the robonix-nav map store; delete_map removes only such folders\n")
            with self._swap_lock():
                self._swap(map_id, stage, target)
        except Exception as exc:
            shutil.rmtree(stage, ignore_errors=True)
            reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
            raise MapStoreError(f"cannot save map {map_id!r} to {target}: {reason}") from None
        return target

    def _swap(self, map_id: str, stage: Path, target: Path) -> None:
        """Move the existing map aside, the staged one in, and delete the old one; on failure put it back."""
        old = None
        if target.exists() or target.is_symlink():
            if not is_map_folder(target):
                raise MapStoreError(f"{target} exists and was not written by the map store (no {MARKER} marker); "
                                    "choose another map_id")
            old = self.root / f".{map_id}.old-{os.getpid()}-{time.monotonic_ns()}"
            os.rename(target, old)
        try:
            os.rename(stage, target)
        except OSError:
            if old is not None:
                os.rename(old, target)
            raise
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)

    def load(self, map_id: str, with_session: bool) -> LoadedMap:
        folder = self.path(map_id)
        if folder.is_symlink():  # a saved map is a real folder; a link may lead anywhere on the machine
            raise MapInvalidError(f"map_id: {folder} is a symbolic link, not a map folder of {self.root}")
        if not folder.is_dir():
            raise MapStoreError(f"no map {map_id!r} in {self.root}")
        try:
            grid = load_map_yaml(folder / MAP_YAML, image_root=folder)
        except MapFileError as exc:
            raise MapInvalidError(str(exc)) from None
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
            path = folder / META
            if path.stat().st_size > META_MAX_BYTES:
                return {}
            meta = json.loads(path.read_text())
            return meta if isinstance(meta, dict) else {}
        except (OSError, ValueError, RecursionError):
            return {}

    def list(self) -> list[dict[str, Any]]:
        """One entry per map folder (hidden staging folders skipped), newest first; at most
        :data:`LIST_MAX_ENTRIES` entries and :data:`LIST_MAX_BYTES` of JSON (see :meth:`listing`)."""
        return self.listing()[0]

    def listing(self) -> tuple[list[dict[str, Any]], int]:
        """``(entries, total)``: the newest maps that fit the caps, and how many map folders there are."""
        out: list[dict[str, Any]] = []
        if not self.root.is_dir():
            return out, 0
        for folder in self.root.iterdir():
            if folder.name.startswith(".") or not folder.is_dir() or folder.is_symlink():
                continue
            try:
                check_id(folder.name)
            except MapIdError:
                continue
            meta = self._meta(folder)
            note = meta.get("note", "")
            note = note[:NOTE_MAX] if isinstance(note, str) else ""
            created = meta.get("created")
            entry = {"map_id": folder.name, "path": str(folder), "note": note,
                     "created": created if isinstance(created, int | float) else None,
                     "resolution": meta.get("resolution"), "width": meta.get("width"), "height": meta.get("height"),
                     "has_session": (folder / SESSION).is_file(), "valid": (folder / MAP_YAML).is_file(),
                     "managed": (folder / MARKER).is_file()}
            out.append(entry)
        out.sort(key=lambda e: -(e["created"] or 0.0))
        kept: list[dict[str, Any]] = []
        size = 2
        for entry in out[:LIST_MAX_ENTRIES]:
            size += len(json.dumps(entry)) + 2
            if size > LIST_MAX_BYTES:
                break
            kept.append(entry)
        return kept, len(out)

    def delete(self, map_id: str) -> None:
        """Delete a map folder the store wrote; any other folder (no marker, a symlink) is refused."""
        folder = self.path(map_id)
        if not folder.is_dir():
            raise MapStoreError(f"no map {map_id!r} in {self.root}")
        if not is_map_folder(folder):
            raise MapStoreError(f"{folder} was not written by the map store (no {MARKER} marker); not deleted")
        self._check_root()
        with _id_lock(self.root, map_id):
            try:
                with self._swap_lock():
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
    """The running session's crash copy: ``<map_dir>/.autosave/<deployment>/<instance>/session.npz``.

    ``deployment`` (``robonix_api.runstate.deployment_key()``: deploy name + atlas address, file-name safe)
    keeps two deployments sharing a maps root apart: both name their mapping service ``mapping``, and one
    must never resume the other's map after a crash (issue 37 item 2). "" (not under ``rbnx boot``):
    ``<map_dir>/.autosave/<instance>/``.

    Written atomically (temp file + ``os.replace``), so a kill in the middle leaves the previous copy;
    read back when ``rbnx boot`` restarts the service after a crash (``RBNX_RESTARTS`` > 0). Hidden from
    ``list_maps`` (a dot folder) and never a saved map: ``save_map`` is still how a map is kept.
    """

    def __init__(self, map_dir: str | os.PathLike[str], instance: str, deployment: str = "") -> None:
        base = Path(map_dir).expanduser() / AUTOSAVE_DIR
        self.folder = (base / check_id(deployment) if deployment else base) / check_id(instance)
        self.path = self.folder / SESSION

    def write(self, session: SessionData) -> Path:
        from slam_service.session_io import save_session

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
        with suppress(OSError):
            self.path.unlink(missing_ok=True)


def resume_engine(session: SessionData, slam_cfg: SlamConfig) -> tuple[SlamEngine, tuple[float, float, float]]:
    """A mapping engine continuing ``session``, and map->odom at its last node (pose ∘ odom⁻¹).

    The odometry source kept running while SLAM was down, so the robot's map pose at the first scan after
    the restart is this map->odom composed with the odometry then (the caller's loop does that)."""
    from robonix_common.geometry import compose, inverse

    engine = SlamEngine(slam_cfg, "mapping")
    engine.load(session=session, mode="mapping")
    last_node = session.graph.n_nodes > 0
    m2o = compose(session.graph.poses[-1], inverse(session.odom[-1])) if last_node else engine.map_to_odom()
    return engine, (float(m2o[0]), float(m2o[1]), float(m2o[2]))
