"""A read-only install run by a user whose HOME does not exist: numba's cache falls back with ONE warning
line instead of ``RuntimeError: cannot cache function '_pack': no locator available`` at import; with no
writable place at all the kernels compile in memory (again one line). Runs the built wheel installed into
a root-owned, read-only venv, as an unprivileged uid (``setpriv``), so it needs root."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest

pytestmark = [pytest.mark.integration, pytest.mark.slow, pytest.mark.timeout(1200),
              pytest.mark.skipif(os.geteuid() != 0 or shutil.which("setpriv") is None,
                                 reason="needs root and setpriv to run as another user")]
REPO = Path(__file__).resolve().parents[4]
KERNEL = ("import numpy as np, nav2_wrapper.core, slam_service.core, os\n"
          "from nav2_wrapper.core._mppi_kernels import limit_and_rollout\n"
          "u = np.zeros((2, 3, 3)); v = np.zeros(3)\n"
          "limit_and_rollout(u, v, v, np.ones(3), np.ones(3), 0.05, np.empty_like(u))\n"
          "print('cache', os.environ.get('NUMBA_CACHE_DIR'))\n")


@pytest.fixture(scope="module")
def ro_venv() -> Iterator[Path]:
    top = Path(tempfile.mkdtemp(prefix="robonix-ro-"))  # under /tmp: other users can reach it
    top.chmod(0o755)
    try:
        r = subprocess.run(["bash", str(REPO / "scripts" / "build_wheel.sh"), str(top / "dist")],
                           env=dict(os.environ, PYTHON=sys.executable), capture_output=True, text=True, timeout=300)
        assert r.returncode == 0, r.stderr
        venv = top / "venv"
        subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True, timeout=120)
        r = subprocess.run([str(venv / "bin" / "pip"), "install", "-q", "-c", str(REPO / "constraints.txt"),
                            r.stdout.strip().splitlines()[-1]], capture_output=True, text=True, timeout=900)
        assert r.returncode == 0, r.stderr[-3000:]
        subprocess.run(["chmod", "-R", "a-w,a+rX", str(top)], check=True)
        yield venv
    finally:
        subprocess.run(["chmod", "-R", "u+w", str(top)], check=False)
        shutil.rmtree(top, ignore_errors=True)


def run_as(uid: int, venv: Path, code: str) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("NUMBA_", "XDG_", "PYTHON", "VIRTUAL_ENV"))}
    env["HOME"] = "/nonexistent"
    return subprocess.run(["setpriv", f"--reuid={uid}", f"--regid={uid}", "--clear-groups",
                           str(venv / "bin" / "python"), "-c", code], cwd="/", env=env, capture_output=True,
                          text=True, timeout=900)


def _uid() -> int:
    return 61000 + os.getpid() % 4000  # an unused uid of this run's own: its tmp cache dir is fresh


def test_no_home_falls_back_to_tmp_with_one_warning(ro_venv: Path) -> None:
    uid = _uid()
    shutil.rmtree(f"/tmp/robonix-{uid}", ignore_errors=True)
    try:
        r = run_as(uid, ro_venv, KERNEL)
        assert r.returncode == 0, r.stderr[-3000:]
        assert "no locator available" not in r.stderr
        warnings = [ln for ln in r.stderr.splitlines() if ln.startswith("robonix: JIT cache")]
        assert len(warnings) == 1, r.stderr
        assert f"using /tmp/robonix-{uid}/numba" in warnings[0]
        assert f"cache /tmp/robonix-{uid}/numba" in r.stdout
    finally:
        shutil.rmtree(f"/tmp/robonix-{uid}", ignore_errors=True)


def test_nowhere_writable_compiles_in_memory(ro_venv: Path) -> None:
    uid = _uid() + 1
    blocked = Path(f"/tmp/robonix-{uid}")
    shutil.rmtree(blocked, ignore_errors=True)
    blocked.mkdir(mode=0o555)  # root's and read-only: the tmp fallback is taken too
    try:
        r = run_as(uid, ro_venv, KERNEL)
        assert r.returncode == 0, r.stderr[-3000:]
        warnings = [ln for ln in r.stderr.splitlines() if ln.startswith("robonix: JIT cache")]
        assert warnings == ["robonix: JIT cache: no writable cache directory (package folder, NUMBA_CACHE_DIR, "
                            "XDG_CACHE_HOME, HOME, tmp); compiling in memory, every process compiles again"]
    finally:
        shutil.rmtree(blocked, ignore_errors=True)
