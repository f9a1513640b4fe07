"""Where numba keeps its compiled kernels: chosen once per process, before the first ``@njit(cache=True)``.

numba raises at *import* (``RuntimeError: cannot cache function '_pack': no locator available for file
'…/_search.py'``) when neither the package's ``__pycache__`` nor its user-wide cache dir is writable, as
for a read-only install run by a user without a writable HOME, or a ``--read-only`` container. So the
cores call :func:`configure` first, which picks, in order:

1. ``$NUMBA_CACHE_DIR`` when it is writable (``rbnx boot`` and the container image set one);
2. the package's own folder (numba's default, ``__pycache__`` next to the sources) when writable;
3. ``$XDG_CACHE_HOME/robonix/numba`` or ``~/.cache/robonix/numba`` when they can be created;
4. ``<tmp>/robonix-<uid>/numba``;
5. else no on-disk cache at all: every process compiles in memory.

A ``$NUMBA_CACHE_DIR`` that exists but is read-only (the image's, run with ``--read-only``) is copied into
the first writable choice, so the kernels compiled at image build time are still loaded, not recompiled.
Anything but case 1 and 2 prints ONE warning line saying where the cache went and why.
"""

from __future__ import annotations

import os
import shutil
import sys
import tempfile
from pathlib import Path

_configured: list[str | None] = []


def writable_dir(path: Path) -> bool:
    """``path`` exists or can be created, and a file can be written in it."""
    try:
        path.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=path, prefix=".probe-"):
            return True
    except OSError:
        return False


def candidates(env: dict[str, str] | os._Environ[str]) -> list[Path]:
    """Per-user choices after the package folder, most persistent first."""
    out: list[Path] = []
    if env.get("XDG_CACHE_HOME"):
        out.append(Path(env["XDG_CACHE_HOME"]) / "robonix" / "numba")
    home = env.get("HOME") or os.path.expanduser("~")
    if home and home != "~":
        out.append(Path(home) / ".cache" / "robonix" / "numba")
    uid = os.getuid() if hasattr(os, "getuid") else "user"
    out.append(Path(tempfile.gettempdir()) / f"robonix-{uid}" / "numba")
    return out


def _seed(src: Path, dst: Path) -> bool:
    """Copy a read-only cache's files into the writable one (files already there are kept)."""
    try:
        shutil.copytree(src, dst, dirs_exist_ok=True, copy_function=_copy_if_absent)
        return True
    except (OSError, shutil.Error):
        return False


def _copy_if_absent(src: str, dst: str) -> None:
    """Copy under a temporary name, then rename: another process seeding the same cache (nav2 and SLAM
    start together) sees either no file or a whole one, never half an index."""
    if os.path.exists(dst):
        return
    tmp = f"{dst}.{os.getpid()}.tmp"
    shutil.copy2(src, tmp)
    os.replace(tmp, dst)


def _disable_caching() -> None:
    """Compile in memory only: numba's ``cache=True`` becomes a no-op for this process."""
    from numba.core import dispatcher

    dispatcher.Dispatcher.enable_caching = lambda self: None  # type: ignore[method-assign]


def _apply(chosen: str) -> None:
    os.environ["NUMBA_CACHE_DIR"] = chosen
    if "numba" in sys.modules:  # numba read its config at import: make it read the new directory
        from numba.core import config

        config.reload_config()


def configure(package_dir: Path | None = None, env: dict[str, str] | None = None) -> str | None:
    """Choose the cache directory for this process (once); returns it, None for the package folder or no
    cache. ``package_dir``: the folder whose ``__pycache__`` numba would use by default."""
    if _configured:
        return _configured[0]
    environ = os.environ if env is None else env
    given = environ.get("NUMBA_CACHE_DIR", "").strip()
    seed = None
    if given:
        if writable_dir(Path(given)):
            _configured.append(given)
            return given
        seed = Path(given) if Path(given).is_dir() else None
        os.environ.pop("NUMBA_CACHE_DIR", None)
    elif package_dir is not None and writable_dir(package_dir / "__pycache__"):
        _configured.append(None)
        return None
    for path in candidates(environ):
        if writable_dir(path):
            why = f"{given} is not writable" if given else f"{package_dir or 'the package folder'} is read-only"
            copied = seed is not None and _seed(seed, path)
            _apply(str(path))
            print(f"robonix: JIT cache: {why}; using {path}" + (f" (seeded from {seed})" if copied else ""),
                  file=sys.stderr, flush=True)
            _configured.append(str(path))
            return str(path)
    print("robonix: JIT cache: no writable cache directory (package folder, NUMBA_CACHE_DIR, "
          "XDG_CACHE_HOME, HOME, tmp); compiling in memory, every process compiles again",
          file=sys.stderr, flush=True)
    _disable_caching()
    _configured.append(None)
    return None
