"""Issue 15 acceptance: the built wheel, installed into a fresh virtualenv (not the checkout), runs
`rbnx demo --goals 1` from an empty directory and writes map.png; `rbnx init` writes example deploys
that validate there. This is what `pip install robonix-nav` gives a new user.

Dependencies come from constraints.txt (exact pins), through pip's usual index and cache.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = [pytest.mark.integration, pytest.mark.slow, pytest.mark.timeout(900)]
REPO = Path(__file__).resolve().parents[4]
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def fresh_venv(tmp_path_factory: pytest.TempPathFactory) -> Path:
    tmp = tmp_path_factory.mktemp("wheel")
    r = subprocess.run(["bash", str(REPO / "scripts" / "build_wheel.sh"), str(tmp / "dist")],
                       env=dict(os.environ, PYTHON=sys.executable), capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    wheel = Path(r.stdout.strip().splitlines()[-1])
    venv = tmp / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True, timeout=120)
    r = subprocess.run([str(venv / "bin" / "pip"), "install", "-q", "-c", str(REPO / "constraints.txt"), str(wheel)],
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]
    return venv


def _clean_env(venv: Path, home: Path) -> dict[str, str]:
    """No trace of the checkout: no PYTHONPATH, the fresh venv first on PATH, its own caches."""
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(("PYTHON", "RBNX_", "ROBONIX_", "VIRTUAL_ENV", "NUMBA_", "CYCLONEDDS_"))}
    env.update(PATH=f"{venv / 'bin'}{os.pathsep}{env.get('PATH', '')}", HOME=str(home),
               XDG_CACHE_HOME=str(home / ".cache"), RBNX_STATE_DIR=str(home / "state"))
    return env


def test_installed_wheel_has_no_checkout_behind_it(fresh_venv: Path, tmp_path: Path) -> None:
    code = ("import robonix_nav_data.resources as r, hal_panda_mobile, nav2_wrapper; "
            "print(r.data_root()); print(r.example_deploy()); print(hal_panda_mobile.__file__)")
    r = subprocess.run([str(fresh_venv / "bin" / "python"), "-c", code], cwd=tmp_path,
                       env=_clean_env(fresh_venv, tmp_path), capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    for line in r.stdout.splitlines():
        assert str(fresh_venv) in line, line
        assert str(REPO) not in line, line


def test_demo_from_an_empty_directory(fresh_venv: Path, tmp_path: Path) -> None:
    empty = tmp_path / "empty"
    empty.mkdir()
    r = subprocess.run([str(fresh_venv / "bin" / "rbnx"), "demo", "--goals", "1", "--scene", "kitchen",
                        "--rtf", "2"], cwd=empty, env=_clean_env(fresh_venv, tmp_path), capture_output=True,
                       text=True, timeout=600, stdin=subprocess.DEVNULL)
    assert r.returncode == 0, r.stdout[-4000:] + r.stderr[-4000:]
    assert "1/1 goals succeeded" in r.stdout
    (png,) = empty.glob("rbnx-demo/*/map.png")
    assert png.read_bytes().startswith(PNG_MAGIC)


def test_init_writes_examples_that_validate(fresh_venv: Path, tmp_path: Path) -> None:
    env = _clean_env(fresh_venv, tmp_path)
    rbnx = str(fresh_venv / "bin" / "rbnx")
    r = subprocess.run([rbnx, "init", "mine"], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    deploys = sorted((tmp_path / "mine").glob("*/deploy.yaml"))
    assert [d.parent.name for d in deploys] == ["minimal", "real_robot", "sim"]
    v = subprocess.run([rbnx, "validate", *map(str, deploys)], cwd=tmp_path, env=env, capture_output=True,
                       text=True, timeout=120)
    assert v.returncode == 0, v.stdout + v.stderr
    again = subprocess.run([rbnx, "init", "mine"], cwd=tmp_path, env=env, capture_output=True, text=True,
                           timeout=120)
    assert again.returncode == 2
    assert "already exists" in again.stderr
