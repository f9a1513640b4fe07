"""The repository's own files, for tests that check every manifest or deploy file it ships."""

from __future__ import annotations

from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
SKIP_DIRS = {".git", ".venv", "venv", "node_modules", "rbnx-logs"}


def repo_files(pattern: str) -> list[Path]:
    """Files matching ``pattern`` anywhere in the repository, outside virtualenvs, VCS and log dirs."""
    return sorted(p for p in REPO.rglob(pattern) if not SKIP_DIRS.intersection(p.relative_to(REPO).parts))
