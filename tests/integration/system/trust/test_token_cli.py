"""rbnx's side of the token: the state file is private, commands find the token by atlas address, a stale
token never leaks into a boot with ``auth: none``, ``rbnx token`` fails in one line when there is none."""

from __future__ import annotations

import stat
import subprocess
import sys
from pathlib import Path

import pytest

from rbnx.boot import deploytoken
from rbnx.boot.statefile import write_state
from robonix_api.auth import TOKEN_ENV


def test_state_file_is_private_and_token_is_found_by_atlas(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("RBNX_STATE_DIR", str(tmp_path))
    path = tmp_path / "boot-sim-abc.json"
    path.write_text("{}")
    path.chmod(0o644)  # an older, world-readable file is tightened on rewrite
    write_state(path, {"atlas": "127.0.0.1:50999", "token": "t0k"}, copy_to=tmp_path / "copy.json")
    assert stat.S_IMODE(path.stat().st_mode) == 0o600
    assert stat.S_IMODE((tmp_path / "copy.json").stat().st_mode) == 0o600
    assert deploytoken.token_for_atlas("127.0.0.1:50999") == "t0k"
    assert deploytoken.token_for_atlas("localhost:50999") == "t0k"
    assert deploytoken.token_for_atlas("127.0.0.1:50998") == ""
    assert deploytoken.adopt_for("127.0.0.1:50999") == "t0k"
    import os

    assert os.environ[TOKEN_ENV] == "t0k"


def test_boot_env_drops_a_stale_token_and_passes_allowed_hosts() -> None:
    env = deploytoken.boot_env({TOKEN_ENV: "stale", "X": "1"}, "", ["robot2.local"])
    assert TOKEN_ENV not in env
    assert env["X"] == "1"
    assert env["ROBONIX_ATLAS_ALLOWED_HOSTS"] == "robot2.local"
    assert deploytoken.boot_env({}, "fresh")[TOKEN_ENV] == "fresh"
    a, b = deploytoken.new_token(), deploytoken.new_token()
    assert a != b
    assert len(a) >= 40


def test_rbnx_token_without_a_boot_is_one_line_exit_1(tmp_path: Path) -> None:
    env = {"PATH": "/usr/bin:/bin", "RBNX_STATE_DIR": str(tmp_path), "HOME": str(tmp_path)}
    r = subprocess.run([sys.executable, "-m", "rbnx.cli", "--atlas", "127.0.0.1:1", "token"], env=env,
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 1
    assert r.stdout == ""
    assert r.stderr.count("\n") == 1
    assert "no deployment token recorded" in r.stderr
