"""The build scripts work from a fresh virtualenv, whose setuptools has no ``wheel`` command: they build
with isolation, so pyproject's [build-system] requirements (setuptools>=68, wheel) are what is used.
(Before: ``error: invalid command 'bdist_wheel'`` because --no-build-isolation was passed whenever
setuptools imported.)"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

pytestmark = [pytest.mark.integration, pytest.mark.slow, pytest.mark.timeout(1800)]
REPO = Path(__file__).resolve().parents[4]


@pytest.fixture(scope="module")
def fresh_python(tmp_path_factory: pytest.TempPathFactory) -> Path:
    venv = tmp_path_factory.mktemp("fresh") / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True, timeout=120)
    has_wheel = subprocess.run([str(venv / "bin" / "python"), "-c", "import wheel"], capture_output=True)
    assert has_wheel.returncode != 0, "a fresh venv is expected to lack the 'wheel' package"
    return venv / "bin" / "python"


def test_build_wheel_from_a_fresh_venv(fresh_python: Path, tmp_path: Path) -> None:
    r = subprocess.run(["bash", str(REPO / "scripts" / "build_wheel.sh"), str(tmp_path / "dist")],
                       env=dict(os.environ, PYTHON=str(fresh_python)), capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]
    assert "invalid command 'bdist_wheel'" not in r.stderr
    wheel = Path(r.stdout.strip().splitlines()[-1])
    assert wheel.name.startswith("robonix_nav-")
    names = zipfile.ZipFile(wheel).namelist()
    assert "nav2_wrapper/core/_search.py" in names
    assert "robonix_common/jit_cache.py" in names


@pytest.mark.container
def test_build_image_from_a_fresh_venv(fresh_python: Path) -> None:
    engine = os.environ.get("ROBONIX_CONTAINER_ENGINE", "podman")
    if shutil.which(engine) is None and os.geteuid() != 0:
        pytest.skip("no container engine and not root to install one")
    tag = f"t{os.getpid()}"
    img = f"localhost/robonix-nav2-fresh:{tag}"
    env = dict(os.environ, PYTHON=str(fresh_python), ROBONIX_NAV2_IMAGE=img)
    try:
        r = subprocess.run(["bash", str(REPO / "scripts" / "build_image.sh")], env=env, capture_output=True,
                           text=True, timeout=1700, stdin=subprocess.DEVNULL)
        assert r.returncode == 0, r.stdout + r.stderr[-4000:]
        assert "invalid command 'bdist_wheel'" not in r.stderr
    finally:
        subprocess.run([engine, "rmi", "-f", img], capture_output=True, timeout=300)
