"""Issue 7 acceptance, with real processes: `rbnx boot` of examples/sim/deploy.yaml (atlas + MuJoCo HAL +
SLAM + navigation), one goal over gRPC → SUCCEEDED, SIGINT → every recorded process gone; and the
one-command `rbnx demo` (exit 0, a real map.png, summary.json saying success; exit 130 and nothing left
on Ctrl-C). The kitchen scene keeps each test well under two minutes. The real-time factor stays at
2: on a loaded 2-core machine the navigation process falls behind a faster clock (stale odometry,
collisions at 6x), which is a limit of the machine, not what these tests check."""

from __future__ import annotations

import json
import math
import signal
import subprocess
import time
from pathlib import Path

import pytest
from support.e2e import SIM_DEPLOY, e2e_env, navigate, rbnx_cmd, recorded_pids, wait_until

from robonix_api.atlas_client import AtlasClient
from robonix_api.procs import pid_alive, stop_process
from robonix_api.types import LifecycleState

pytestmark = [pytest.mark.integration, pytest.mark.timeout(300)]

ENTRIES = ("panda_mobile", "mapping", "nav2")
KITCHEN_GOAL = (5.8, 3.0)  # the kitchen's island_east waypoint, 2.9 m from the start pose
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def test_boot_sim_deploy_navigate_one_goal_and_sigint_leaves_nothing(tmp_path: Path) -> None:
    env = e2e_env(tmp_path, RBNX_SIM_SCENE="kitchen", RBNX_SIM_RTF="2")
    out = tmp_path / "boot.out"
    t0 = time.monotonic()
    with open(out, "w") as fh:
        proc = subprocess.Popen(rbnx_cmd() + ["boot", "-f", str(SIM_DEPLOY), "--no-progress",
                                              "--log-dir", str(tmp_path / "logs")],
                                env=env, cwd=tmp_path, stdout=fh, stderr=subprocess.STDOUT,
                                stdin=subprocess.DEVNULL)
    pids: list[tuple[str, int, int | None]] = []
    try:
        def booted() -> bool:
            if proc.poll() is not None:
                raise AssertionError(f"rbnx boot exited {proc.returncode}:\n{out.read_text()}")
            return "3/3 entries ready" in out.read_text()

        wait_until(booted, 150, "the boot summary (3/3 entries ready)")
        (state_file,) = (tmp_path / "state").glob("boot-*.json")
        pids = recorded_pids(state_file)
        assert {name for name, _, _ in pids} >= {"rbnx boot", "atlas", *ENTRIES}
        atlas = json.loads(state_file.read_text())["atlas"]
        token = json.loads(state_file.read_text()).get("token", "")
        assert token, "rbnx boot records the deployment token"
        with AtlasClient(atlas) as client:
            states = {p.id: p.state for p in client.query() if p.id in ENTRIES}
        assert states == dict.fromkeys(ENTRIES, LifecycleState.ACTIVE), states

        state, detail, (gx, gy) = navigate(atlas, *KITCHEN_GOAL, timeout_s=90, token=token)
        assert state == "SUCCEEDED", detail
        assert math.hypot(gx - KITCHEN_GOAL[0], gy - KITCHEN_GOAL[1]) < 0.5, (gx, gy, detail)

        proc.send_signal(signal.SIGINT)
        assert proc.wait(120) == 0, out.read_text()
        wait_until(lambda: not [p for p in pids if pid_alive(p[1], p[2])], 30, "every recorded process to exit")
        assert not list((tmp_path / "state").glob("boot-*.json")), "state file left behind"
        for name in ENTRIES:
            log = (tmp_path / "logs" / f"{name}.log").read_text()
            assert "Traceback" not in log, f"{name}.log:\n{log[-3000:]}"
        print(f"boot + goal + shutdown in {time.monotonic() - t0:.1f}s")
    finally:
        stop_process(proc, 60.0, kill_timeout=30.0, first=signal.SIGINT)   # Ctrl-C is rbnx boot's clean stop


def _run_demo(tmp_path: Path, *args: str, timeout: float = 240) -> subprocess.CompletedProcess[str]:
    return subprocess.run(rbnx_cmd() + ["demo", *args], env=e2e_env(tmp_path), cwd=tmp_path,
                          capture_output=True, text=True, timeout=timeout, stdin=subprocess.DEVNULL)


@pytest.mark.slow
def test_demo_one_goal_writes_map_and_summary(tmp_path: Path) -> None:
    out = tmp_path / "demo"
    r = _run_demo(tmp_path, "--goals", "1", "--rtf", "2", "--scene", "kitchen", "--out", str(out))
    assert r.returncode == 0, r.stdout[-4000:] + r.stderr[-4000:]
    assert "1/1 goals succeeded" in r.stdout

    png = (out / "map.png").read_bytes()
    assert png.startswith(PNG_MAGIC)
    from PIL import Image

    with Image.open(out / "map.png") as img:
        img.verify()
    with Image.open(out / "map.png") as img:
        assert img.width >= 100
        assert img.height >= 100

    summary = json.loads((out / "summary.json").read_text())
    assert summary["success"] is True
    assert summary["goals_succeeded"] == 1
    (goal,) = summary["goals"]
    assert goal["state"] == "SUCCEEDED"
    assert goal["succeeded"] is True
    assert goal["final_error_m"] < 0.5
    assert goal["path_length_m"] > 1.0
    assert goal["collision_count"] == 0
    assert summary["leftover_processes"] == []
    assert summary["boot_exit_code"] == 0
    left = [p for p in recorded_pids(out / "logs" / "rbnx-boot.json") if pid_alive(p[1], p[2])]
    assert not left, left


@pytest.mark.slow
def test_demo_sigint_mid_goal_shuts_down_and_exits_130(tmp_path: Path) -> None:
    out = tmp_path / "demo"
    log = tmp_path / "demo.out"
    with open(log, "w") as fh:
        proc = subprocess.Popen(rbnx_cmd() + ["demo", "--goals", "3", "--rtf", "1", "--scene", "kitchen",
                                              "--out", str(out)],
                                env=e2e_env(tmp_path), cwd=tmp_path, stdout=fh, stderr=subprocess.STDOUT,
                                stdin=subprocess.DEVNULL)
    try:
        wait_until(lambda: "RUNNING" in log.read_text() or proc.poll() is not None, 150, "goal 1 to run")
        assert proc.poll() is None, log.read_text()
        proc.send_signal(signal.SIGINT)
        assert proc.wait(120) == 130, log.read_text()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(30)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["interrupted"] is True
    assert summary["success"] is False
    assert summary["goals"][0]["state"] == "CANCELED"
    assert summary["leftover_processes"] == []
    left = [p for p in recorded_pids(out / "logs" / "rbnx-boot.json") if pid_alive(p[1], p[2])]
    assert not left, left
