"""Importing this chooses numba's cache directory for the process (see :mod:`robonix_common.jit_cache`).

The numba cores import it first, before any ``@njit(cache=True)`` is decorated. The installed packages live
side by side, so this package's folder stands for theirs when deciding whether ``__pycache__`` is writable.
"""

from pathlib import Path

from robonix_common.jit_cache import configure

CACHE_DIR = configure(Path(__file__).parent)
