"""`rbnx demo` without a running system: user mistakes exit 2 with one line and start nothing."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest
from support.e2e import e2e_env, rbnx_cmd

# A 4 x 4 m room whose one waypoint is the start: nothing to navigate to (generated random:N scenes always have
# two rooms or more, so the refusal is shown with a scene file).
ONE_ROOM = """
name: one_room
bounds: [0, 0, 4, 4]
walls:
- {start: [0, 0], end: [4, 0]}
- {start: [4, 0], end: [4, 4]}
- {start: [4, 4], end: [0, 4]}
- {start: [0, 4], end: [0, 0]}
start: [2, 2, 0]
waypoints: {centre: [2.2, 2]}
"""


@pytest.mark.parametrize(("args", "message"), [
    (["--scene", "moon_base"], "available: apartment"),
    (["--deploy", "missing.yaml"], "missing.yaml not found"),
    (["--goals", "0"], "--goals"),
    (["--rtf", "-1"], "--rtf"),
    (["--scene", "SCENE_YAML"], "no waypoint farther than 1 m"),   # its only waypoint is the start
])
def test_demo_usage_errors_exit_2_and_start_nothing(tmp_path: Path, args: list[str], message: str) -> None:
    (tmp_path / "one_room.yaml").write_text(ONE_ROOM)
    args = [str(tmp_path / "one_room.yaml") if a == "SCENE_YAML" else a for a in args]
    r = subprocess.run(rbnx_cmd() + ["demo", *args, "--out", str(tmp_path / "out")], env=e2e_env(tmp_path),
                       cwd=tmp_path, capture_output=True, text=True, timeout=60)
    assert r.returncode == 2, r.stdout + r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1, r.stderr
    assert message in lines[0], r.stderr
    assert not (tmp_path / "out").exists()
