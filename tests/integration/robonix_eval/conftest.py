"""The editable install may predate robonix_eval (its finder maps packages at install time): fall back to
the repository root so the suite runs before a reinstall."""

import sys
from pathlib import Path

try:
    import robonix_eval  # noqa: F401
except ImportError:  # pragma: no cover - depends on how the venv was built
    sys.path.insert(0, str(Path(__file__).resolve().parents[3]))
