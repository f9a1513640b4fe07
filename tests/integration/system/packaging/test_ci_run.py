""".ci/run's verdict: the part after installing and linting runs the two pytest suites; with a ``python`` that
answers pytest's "no tests collected" (exit code 5) the run must fail, and with one that passes it must pass."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import pytest
from support.repo import REPO

CI = REPO / ".ci" / "run"


def _suites_part() -> str:
    text = CI.read_text()
    start = text.index("status=0")
    return text[start:]


@pytest.mark.parametrize(("code", "expected"), [(5, 1), (1, 1), (0, 0)])
def test_ci_fails_unless_both_suites_pass(tmp_path: Path, code: int, expected: int) -> None:
    fake = tmp_path / "bin"
    fake.mkdir()
    (fake / "python").write_text(f'#!/bin/sh\necho "$@" >> "{tmp_path}/calls"\nexit {code}\n')
    (fake / "python").chmod(0o755)
    r = subprocess.run(["bash", "-euo", "pipefail", "-c", _suites_part()], cwd=REPO, capture_output=True,
                       text=True, env={**os.environ, "PATH": f"{fake}:{os.environ['PATH']}"}, timeout=60, check=False)
    assert r.returncode == expected, r.stdout + r.stderr
    calls = (tmp_path / "calls").read_text().splitlines()
    assert calls == ["-m pytest -q", "-m pytest -q -m slow or container or fuzz"], calls
