"""`rbnx demo` without a running system: user mistakes exit 2 with one line and start nothing."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest
from support.e2e import e2e_env, rbnx_cmd


@pytest.mark.parametrize(("args", "message"), [
    (["--scene", "moon_base"], "available: apartment"),
    (["--deploy", "missing.yaml"], "missing.yaml not found"),
    (["--goals", "0"], "--goals"),
    (["--rtf", "-1"], "--rtf"),
    (["--scene", "random:23"], "no waypoint farther than 1 m"),   # its only waypoint is the start
])
def test_demo_usage_errors_exit_2_and_start_nothing(tmp_path: Path, args: list[str], message: str) -> None:
    r = subprocess.run(rbnx_cmd() + ["demo", *args, "--out", str(tmp_path / "out")], env=e2e_env(tmp_path),
                       cwd=tmp_path, capture_output=True, text=True, timeout=60)
    assert r.returncode == 2, r.stdout + r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1, r.stderr
    assert message in lines[0], r.stderr
    assert not (tmp_path / "out").exists()
