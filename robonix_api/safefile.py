"""Reading a file named by a caller (a Driver config, a map YAML) without trusting the name.

A path that comes over the wire may point at ``/dev/zero``, a FIFO, a multi-gigabyte file or, through a
symlink, anywhere on the machine. :func:`read_capped` reads only a regular file that resolves under one of
the allowed roots, and checks its size on the open descriptor BEFORE reading (then reads at most the cap,
so a file growing meanwhile cannot take more). Errors are :class:`UnsafeFileError` whose message starts
with the field at fault.
"""

from __future__ import annotations

import os
import stat
from collections.abc import Iterable
from pathlib import Path


class UnsafeFileError(ValueError):
    """The file is not one we may read; the message names the field and says why."""


def inside(path: Path, roots: Iterable[Path]) -> bool:
    """Whether ``path`` (resolved, symlinks followed) is one of ``roots`` or lies under one of them."""
    real = path.resolve()
    for root in roots:
        base = Path(root).resolve()
        if real == base or real.is_relative_to(base):
            return True
    return False


def check_under(path: str | os.PathLike[str], roots: Iterable[Path], field: str) -> Path:
    """``path`` resolved, or UnsafeFileError naming ``field`` when it resolves outside every root."""
    roots = list(roots)
    try:
        real = Path(path).expanduser().resolve()
    except (OSError, RuntimeError, ValueError) as exc:  # symlink loops, NUL bytes
        raise UnsafeFileError(f"{field}: {str(path)[:200]} cannot be resolved: {exc}") from None
    if not inside(real, roots):
        shown = ", ".join(str(r) for r in roots) or "(none)"
        raise UnsafeFileError(f"{field}: {str(path)[:200]} resolves to {str(real)[:200]}, outside the allowed "
                              f"folders ({shown})")
    return real


def read_capped(path: str | os.PathLike[str], max_bytes: int, field: str,
                roots: Iterable[Path] | None = None) -> bytes:
    """The bytes of a regular file of at most ``max_bytes`` (under ``roots`` when given).

    The type and size are checked with ``fstat`` on the opened descriptor (no race with a swapped
    name); a FIFO is opened non-blocking so that opening it cannot hang.
    """
    p = check_under(path, roots, field) if roots is not None else Path(path)
    try:
        fd = os.open(p, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except OSError as exc:
        raise UnsafeFileError(f"{field}: cannot open {str(path)[:200]}: {exc.strerror or exc}") from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise UnsafeFileError(f"{field}: {str(path)[:200]} is not a regular file")
        if st.st_size > max_bytes:
            raise UnsafeFileError(f"{field}: {str(path)[:200]} is {st.st_size} bytes, more than the "
                                  f"{max_bytes} allowed")
        chunks, left = [], max_bytes + 1
        while left > 0:
            chunk = os.read(fd, min(left, 1 << 20))
            if not chunk:
                break
            chunks.append(chunk)
            left -= len(chunk)
        data = b"".join(chunks)
        if len(data) > max_bytes:
            raise UnsafeFileError(f"{field}: {str(path)[:200]} grew beyond {max_bytes} bytes while read")
        return data
    except OSError as exc:
        raise UnsafeFileError(f"{field}: cannot read {str(path)[:200]}: {exc.strerror or exc}") from None
    finally:
        os.close(fd)


__all__ = ["UnsafeFileError", "check_under", "inside", "read_capped"]
