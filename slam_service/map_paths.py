"""Where saved maps may live, and what a map id may be: the file-system boundary of the map store.

Any local process can send CMD_INIT with a ``map_dir`` and then call ``save_map`` / ``delete_map``, so
the map store must never write or delete outside one configured folder, the **maps root**
(``$ROBONIX_MAPS_ROOT``, default ``$XDG_DATA_HOME/robonix/maps``, i.e. ``~/.local/share/robonix/maps``).
``map_dir`` is resolved (``~``, symlinks, ``..``) before it is compared with the resolved root, so a
symlink inside the root that points out of it is refused too. Map ids are plain names checked over the
whole string (``re.fullmatch``: a trailing newline is not a name). A folder the store wrote holds the
marker file :data:`MARKER`; only such folders are ever replaced or deleted.

Staging folders of a save (``.<id>.saving-<pid>-…``, ``.<id>.old-<pid>-…``) carry the writer's pid, so
leftovers of a killed save are told apart from a save running in another live process and cleaned.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

from robonix_api.validation import ID_MAX, NOTE_MAX, clip

#: A map id: a letter or digit, then letters, digits, ``.``, ``_``, ``-``; 64 characters at most.
MAP_ID_MAX = ID_MAX
_ID = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]{0,63}")
#: Written into every folder the map store saves; ``delete_map`` deletes only folders holding it.
MARKER = ".robonix-map"
_STAGE = re.compile(r"\.(?P<id>[A-Za-z0-9][A-Za-z0-9._-]{0,63})\.(?P<kind>saving|old)-(?P<pid>\d+)-.*")
_LEGACY_STAGE = re.compile(r"\.(?P<id>[A-Za-z0-9][A-Za-z0-9._-]{0,63})\.(?P<kind>saving|old)-.*")


class MapIdError(ValueError):
    """The map id is not a plain name (path separators, '..', empty, too long, control characters)."""


__all__ = ["MAP_ID_MAX", "MARKER", "NOTE_MAX", "MapDirError", "MapIdError", "check_id", "check_note", "clip",
           "default_maps_root", "is_map_folder", "resolve_map_dir", "stale_staging"]


class MapDirError(ValueError):
    """``map_dir`` lies outside the maps root (or cannot be resolved)."""


def check_id(map_id: str) -> str:
    """``map_id`` itself, or MapIdError naming the field (the offending value clipped)."""
    if not isinstance(map_id, str) or len(map_id) > MAP_ID_MAX or not _ID.fullmatch(map_id) or ".." in map_id:
        raise MapIdError(f"map_id: {clip(map_id)} is not a valid name (letters, digits, '.', '_', '-'; starts "
                         f"with a letter or digit; no path separators or '..'; at most {MAP_ID_MAX} characters)")
    return map_id


def check_note(note: str) -> str:
    """``note`` itself, or ValueError naming the field when longer than ``NOTE_MAX`` (4096) bytes."""
    size = len(note.encode("utf-8", "surrogatepass"))
    if size > NOTE_MAX:
        raise ValueError(f"note: at most {NOTE_MAX} bytes, got {size}")
    return note


def default_maps_root() -> Path:
    """``$ROBONIX_MAPS_ROOT``, else ``$XDG_DATA_HOME/robonix/maps`` (``~/.local/share/robonix/maps``)."""
    env = os.environ.get("ROBONIX_MAPS_ROOT", "").strip()
    if env:
        return Path(env).expanduser()
    data = os.environ.get("XDG_DATA_HOME", "").strip()
    base = Path(data).expanduser() if data and Path(data).is_absolute() else Path.home() / ".local/share"
    return base / "robonix" / "maps"


def resolve_map_dir(map_dir: str | os.PathLike[str], root: str | os.PathLike[str] | None = None) -> Path:
    """The absolute, symlink-free folder for ``map_dir``; relative paths are taken inside the root.

    MapDirError naming ``map_dir`` when the resolved folder is not the root or inside it.
    """
    root_path = Path(root).expanduser() if root is not None else default_maps_root()
    try:
        real_root = root_path.resolve()
        given = Path(map_dir).expanduser()
        real = (given if given.is_absolute() else real_root / given).resolve()
    except (OSError, RuntimeError, ValueError) as exc:  # symlink loops, NUL bytes
        raise MapDirError(f"map_dir: {clip(str(map_dir))} cannot be resolved: {exc}") from None
    if real != real_root and not real.is_relative_to(real_root):
        raise MapDirError(f"map_dir: {clip(str(map_dir))} resolves to {clip(str(real))}, outside the maps root "
                          f"{real_root} (set ROBONIX_MAPS_ROOT to store maps elsewhere)")
    return real


def is_map_folder(folder: Path) -> bool:
    """True for a real folder (not a symlink) holding the store's marker file."""
    marker = folder / MARKER
    return folder.is_dir() and not folder.is_symlink() and marker.is_file() and not marker.is_symlink()


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def stale_staging(folder: Path) -> list[tuple[Path, str, str]]:
    """``(path, map_id, kind)`` of staging folders whose writer is gone (kind ``saving`` or ``old``).

    A name with a live pid belongs to a save in progress (maybe in another process) and is left alone.
    """
    out: list[tuple[Path, str, str]] = []
    try:
        entries = list(folder.iterdir())
    except OSError:
        return out
    for entry in entries:
        m = _STAGE.fullmatch(entry.name)
        if m is not None:
            if _alive(int(m["pid"])):
                continue
        else:
            m = _LEGACY_STAGE.fullmatch(entry.name)  # written before pids were in the name
            if m is None:
                continue
        if entry.is_dir() and not entry.is_symlink():
            out.append((entry, m["id"], m["kind"]))
    return out
