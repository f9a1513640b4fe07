"""Run code in a fresh interpreter where chosen packages cannot be imported.

How the purity tests prove an algorithm core needs no middleware or file-format stack: a ``sys.meta_path``
finder makes the blocked top-level packages raise ImportError, and a fresh interpreter means nothing this
test run already imported can hide a dependency. The code run after the finder sees ``BLOCKED``.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
#: What an algorithm core must not need: gRPC, DDS, MCP and the file-format libraries.
MIDDLEWARE_AND_FORMATS = ("grpc", "cyclonedds", "mcp", "yaml", "pydantic", "PIL")


def blocker_source(blocked: tuple[str, ...]) -> str:
    """Python source that installs the blocking finder and defines ``BLOCKED``."""
    return f"""
import sys
BLOCKED = {tuple(blocked)!r}

class _Blocker:
    def find_spec(self, name, path=None, target=None):
        if name.partition(".")[0] in BLOCKED:
            raise ImportError(f"{{name}} is blocked in this purity check")
        return None

sys.meta_path.insert(0, _Blocker())
"""


def run_blocked(body: str, blocked: tuple[str, ...] = MIDDLEWARE_AND_FORMATS,
                timeout: float = 300.0) -> subprocess.CompletedProcess[str]:
    """Run ``body`` (Python source) in a fresh interpreter after the finder is installed."""
    return subprocess.run([sys.executable, "-c", blocker_source(blocked) + body], capture_output=True, text=True,
                          timeout=timeout, cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT)}, check=False)
