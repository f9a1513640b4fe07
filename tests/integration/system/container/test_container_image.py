"""Issue 15 acceptance: the container image, built for real from nothing and run for real.

scripts/build_image.sh makes the Debian base rootfs with debootstrap (no registry is reachable), imports
it, builds docker/Dockerfile on it (the project's wheel + pinned dependencies, non-root user, numba
kernels compiled at build time) and the test runs `rbnx demo --goals 1` inside with no network at all:
DDS and gRPC stay on the container's own loopback. The engine is Debian's podman (runc runtime),
installed by scripts/install_engine.sh when absent (needs root, as in CI).

Downloads are cached between runs (debootstrap's .debs and the dependency wheels under the user cache
dir); the base rootfs and the image are rebuilt each time under tags of this test's own.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from robonix_api.procs import stop_process

pytestmark = [pytest.mark.integration, pytest.mark.container, pytest.mark.timeout(1500)]
REPO = Path(__file__).resolve().parents[4]
ENGINE = os.environ.get("ROBONIX_CONTAINER_ENGINE", "podman")


def _engine(*args: str, timeout: float = 600) -> subprocess.CompletedProcess[str]:
    return subprocess.run([ENGINE, *args], capture_output=True, text=True, timeout=timeout,
                          stdin=subprocess.DEVNULL)


@pytest.fixture(scope="module")
def image() -> str:
    if shutil.which(ENGINE) is None:
        r = subprocess.run(["bash", str(REPO / "scripts" / "install_engine.sh")], capture_output=True, text=True,
                           timeout=900)
        assert r.returncode == 0, f"cannot install the container engine: {r.stderr[-2000:]}"
    tag = f"t{os.getpid()}"
    base, img = f"localhost/robonix-base-test:{tag}", f"localhost/robonix-nav2-test:{tag}"
    env = dict(os.environ, PYTHON=sys.executable, ROBONIX_CONTAINER_ENGINE=ENGINE, ROBONIX_BASE_IMAGE=base,
               ROBONIX_NAV2_IMAGE=img, ROBONIX_BASE_REBUILD="1")
    try:
        r = subprocess.run(["bash", str(REPO / "scripts" / "build_image.sh")], env=env, capture_output=True,
                           text=True, timeout=1200, stdin=subprocess.DEVNULL)
        print(r.stdout)  # the per-step timings
        assert r.returncode == 0, r.stdout + r.stderr[-4000:]
        yield img
    finally:
        _engine("rmi", "-f", img, base, timeout=300)


def _run(img: str, *cmd: str, timeout: float = 600) -> subprocess.CompletedProcess[str]:
    return _engine("run", "--rm", "--pull=never", "--network", "none", "--no-healthcheck", img, *cmd,
                   timeout=timeout)


def test_image_runs_the_installed_wheel_as_non_root_with_a_warm_numba_cache(image: str) -> None:
    code = ("import os, nav2_wrapper, robonix_nav_data.resources as r; print(os.getuid()); "
            "print(nav2_wrapper.__file__); print(r.example_deploy()); "
            "print(sum(n.endswith('.nbi') for _, _, f in os.walk(os.environ['NUMBA_CACHE_DIR']) for n in f))")
    r = _run(image, "python", "-c", code, timeout=120)
    assert r.returncode == 0, r.stderr
    uid, module, deploy, indexes = r.stdout.split()
    assert uid != "0"
    assert "/site-packages/" in module
    assert "/site-packages/" in deploy
    assert int(indexes) >= 4  # the planner's kernels were compiled at build time


def test_demo_one_goal_inside_with_no_network(image: str) -> None:
    r = _run(image, "rbnx", "demo", "--goals", "1", "--scene", "kitchen", "--rtf", "2",
             "--out", "/var/lib/robonix/demo")
    assert r.returncode == 0, r.stdout[-4000:] + r.stderr[-4000:]
    assert "1/1 goals succeeded" in r.stdout
    assert "map /var/lib/robonix/demo/map.png" in r.stdout


def test_sim_deploy_with_nav2_in_the_container(image: str, tmp_path: Path) -> None:
    """The docker target as `rbnx boot` runs it: scripts/start.sh starts nav2 from the image (host network,
    DDS config and domain forwarded) beside the host's atlas, HAL and SLAM; a goal succeeds; shutdown
    removes the container (scripts/stop.sh)."""
    sys.path.insert(0, str(REPO / "tests"))
    from support.e2e import e2e_env, navigate, rbnx_cmd, wait_until

    from robonix_nav_data import resources

    (deploy,) = resources.copy_examples(tmp_path / "ex", ("sim",))
    deploy.write_text(deploy.read_text().replace("ROBONIX_NAV2_FORCE: native", "ROBONIX_NAV2_FORCE: docker"))
    env = e2e_env(tmp_path, RBNX_SIM_SCENE="kitchen", RBNX_SIM_RTF="2", ROBONIX_NAV2_IMAGE=image,
                  ROBONIX_CONTAINER_ENGINE=ENGINE)
    out = tmp_path / "boot.out"
    with open(out, "w") as fh:
        proc = subprocess.Popen(rbnx_cmd() + ["boot", "-f", str(deploy), "--no-progress", "--log-dir",
                                              str(tmp_path / "logs")], env=env, cwd=tmp_path, stdout=fh,
                                stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
    try:
        def booted() -> bool:
            assert proc.poll() is None, out.read_text()
            return "3/3 entries ready" in out.read_text()

        wait_until(booted, 240, "the boot with nav2 in the container")
        names = _engine("ps", "--format", "{{.Names}} {{.Image}}", timeout=60).stdout
        assert "robonix-nav2-nav2-sim-navigation-" in names, names
        assert image in names, names
        (state,) = (tmp_path / "state").glob("boot-*.json")
        state, detail, _ = navigate(json.loads(state.read_text())["atlas"], 5.8, 3.0, timeout_s=150,
                                   token=json.loads(state.read_text()).get("token", ""))
        assert state == "SUCCEEDED", detail
        proc.send_signal(signal.SIGINT)
        assert proc.wait(120) == 0, out.read_text()
        left = _engine("ps", "-a", "--format", "{{.Names}}", timeout=60).stdout
        assert "robonix-nav2-nav2-sim-navigation-" not in left, left
    finally:
        stop_process(proc, 60.0, kill_timeout=30.0, first=signal.SIGINT)   # Ctrl-C is rbnx boot's clean stop


def _run_ro(img: str, *cmd: str, timeout: float = 900) -> subprocess.CompletedProcess[str]:
    """``--read-only``: podman then mounts a tmpfs on /tmp (and /run, /var/tmp), nothing else is writable."""
    return _engine("run", "--rm", "--pull=never", "--network", "none", "--no-healthcheck", "--read-only", img,
                   *cmd, timeout=timeout)


def test_read_only_container_loads_the_shipped_kernels(image: str) -> None:
    """The image's compiled kernels seed a writable cache in /tmp: one line says so, nothing recompiles."""
    code = ("import time; t = time.perf_counter(); import nav2_wrapper.core.warmup as w; "
            "w.compile_kernels(); print('warm', round(time.perf_counter() - t, 1))")
    r = _run_ro(image, "python", "-c", code, timeout=300)
    assert r.returncode == 0, r.stderr[-3000:]
    lines = [ln for ln in r.stderr.splitlines() if ln.startswith("robonix: JIT cache")]
    assert lines == ["robonix: JIT cache: /var/cache/robonix/numba is not writable; using "
                     "/tmp/robonix-10001/numba (seeded from /var/cache/robonix/numba)"], r.stderr


def test_read_only_demo_needs_out_and_runs_with_tmpfs_out(image: str) -> None:
    r = _run_ro(image, "rbnx", "demo", "--goals", "1", timeout=120)
    assert r.returncode == 2, r.stdout + r.stderr
    assert len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert "/var/lib/robonix/rbnx-demo/" in r.stderr
    assert "--out" in r.stderr
    assert "Traceback" not in r.stderr
    r = _run_ro(image, "rbnx", "demo", "--goals", "1", "--scene", "kitchen", "--rtf", "2", "--out", "/tmp/out")
    assert r.returncode == 0, r.stdout[-4000:] + r.stderr[-4000:]
    assert "1/1 goals succeeded" in r.stdout
