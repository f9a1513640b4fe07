"""Units for side-by-side deployments and shipped resources: state-file and run-dir keys, finding the
one running boot of a deployment, the child environment, and `rbnx init`'s copies of the examples."""

from __future__ import annotations

from pathlib import Path

import pytest

from rbnx.boot.deployment import StateNotFound, locate_state
from rbnx.boot.entry import EntryRunner, Timing
from rbnx.boot.statefile import deployment_key, find_states, run_dir, state_path, write_state
from rbnx.models import load_deploy
from robonix_nav_data import resources


@pytest.fixture
def state_dir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setenv("RBNX_STATE_DIR", str(tmp_path / "state"))
    return tmp_path / "state"


def test_state_file_is_keyed_by_deploy_and_listen_address(state_dir: Path) -> None:
    deploy = Path("/x/deploy.yaml")
    a, b = state_path(deploy, "127.0.0.1:50061"), state_path(deploy, "127.0.0.1:50062")
    assert a != b
    assert a.parent == b.parent == state_dir
    assert state_path(deploy, "127.0.0.1:50061", pid=7) == a  # a fixed port: one deployment, no PID
    p0, p1 = state_path(deploy, "127.0.0.1:0", pid=7), state_path(deploy, "127.0.0.1:0", pid=8)
    assert p0 != p1  # OS-picked ports: every boot is its own deployment
    write_state(p0, {"pid": 7})
    write_state(p1, {"pid": 8})
    assert find_states(deploy, "127.0.0.1:0") == sorted([p0, p1])
    assert find_states(deploy, "127.0.0.1:50061") == []


def test_run_dir_is_keyed_by_deploy_name_and_atlas_address(tmp_path: Path) -> None:
    env = {"XDG_RUNTIME_DIR": str(tmp_path)}
    a, b = run_dir("sim", "127.0.0.1:50061", env), run_dir("sim", "127.0.0.1:50062", env)
    assert a != b
    assert a.parent == b.parent == tmp_path / "robonix"
    assert a.name == deployment_key("sim", "127.0.0.1:50061") == "sim-127.0.0.1_50061"
    assert run_dir("sim", "127.0.0.1:50061", {"RBNX_RUN_DIR": str(tmp_path / "r")}).parent == tmp_path / "r"
    assert "/" not in deployment_key("a/b c", "[::1]:5")


def _sim_deploy(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, listen: str) -> Path:
    monkeypatch.setenv("RBNX_ATLAS_LISTEN", listen)
    return resources.example_deploy("sim")


def test_locate_state_never_picks_another_deployment(state_dir: Path, tmp_path: Path,
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    deploy = _sim_deploy(tmp_path, monkeypatch, "127.0.0.1:50062")
    write_state(state_path(deploy, "127.0.0.1:50061"), {"pid": 1, "atlas": "127.0.0.1:50061"})
    with pytest.raises(StateNotFound, match="with atlas 127.0.0.1:50062"):
        locate_state(deploy)  # only A runs; B's environment must not find it
    mine = state_path(deploy, "127.0.0.1:50062")
    write_state(mine, {"pid": 2, "atlas": "127.0.0.1:50062"})
    assert locate_state(deploy) == mine


def test_locate_state_with_several_port_zero_boots_needs_the_atlas(state_dir: Path, tmp_path: Path,
                                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    deploy = _sim_deploy(tmp_path, monkeypatch, "127.0.0.1:0")
    for pid, port in ((11, 41001), (12, 41002)):
        write_state(state_path(deploy, "127.0.0.1:0", pid=pid), {"pid": pid, "atlas": f"127.0.0.1:{port}"})
    with pytest.raises(StateNotFound, match="--atlas"):
        locate_state(deploy)
    assert locate_state(deploy, "127.0.0.1:41002") == state_path(deploy, "127.0.0.1:0", pid=12)


def test_child_env_has_a_deployment_run_dir_and_a_user_numba_cache(tmp_path: Path,
                                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    deploy = load_deploy(_sim_deploy(tmp_path, monkeypatch, "127.0.0.1:0"))
    base = {"RBNX_DEPLOY_NAME": deploy.name, "XDG_RUNTIME_DIR": str(tmp_path / "run"),
            "XDG_CACHE_HOME": str(tmp_path / "cache"), "PATH": "/usr/bin"}
    r = EntryRunner(deploy.entries[0], base, tmp_path / "x.log", Timing())
    env = r.child_env("127.0.0.1:41001")
    assert env["RBNX_RUN_DIR"] == str(tmp_path / "run" / "robonix" / "sim-navigation-127.0.0.1_41001")
    assert env["NUMBA_CACHE_DIR"] == str(tmp_path / "cache" / "robonix-nav" / "numba")
    assert EntryRunner(deploy.entries[0], {**base, "NUMBA_CACHE_DIR": "/mine"}, tmp_path / "x.log",
                       Timing()).child_env("127.0.0.1:1")["NUMBA_CACHE_DIR"] == "/mine"


def test_copied_examples_point_at_the_installed_packages(tmp_path: Path) -> None:
    written = resources.copy_examples(tmp_path / "ex")
    assert sorted(p.parent.name for p in written) == ["minimal", "real_robot", "sim"]
    sim = load_deploy(tmp_path / "ex" / "sim" / "deploy.yaml")
    roots = {e.name: e.root for e in sim.entries}
    assert roots["panda_mobile"] == resources.example_deploy("sim").parents[2] / "hal_panda_mobile"
    assert all(r.is_absolute() and (r / "package_manifest.yaml").is_file() for r in roots.values())
    text = (tmp_path / "ex" / "sim" / "deploy.yaml").read_text()
    assert "path: ${RBNX_DATA_ROOT}/hal_panda_mobile" in text  # portable: no site-packages path written
    assert str(resources.data_root()) not in text
    assert "examples/sim" not in text  # comments name the copy
    assert "rbnx boot -f sim/deploy.yaml" in text
    minimal = (tmp_path / "ex" / "minimal" / "deploy.yaml").read_text()
    assert "path: odom_consumer" in minimal  # the example's own packages stay relative
    assert "# Minimal deploy" in minimal  # comments kept
    with pytest.raises(FileExistsError):
        resources.copy_examples(tmp_path / "ex", ("sim",))
