"""Acceptance: the real `rbnx boot` subprocess with the minimal example (B listed before A).

Everything is polled with generous deadlines; processes are checked by the PIDs/PGIDs rbnx recorded in
its state file, through /proc.
"""

from __future__ import annotations

import json
import signal
import socket
import subprocess
from pathlib import Path
from typing import Any

import pytest
from support.wait import wait_until

from .rbnx_testutil import alive, copy_minimal, group_alive, make_env, rbnx_cmd, run

pytestmark = pytest.mark.integration
SUMMARY = "boot: 2/2 entries ready"


class Boot:
    """A background `rbnx boot` with its output in a file."""

    def __init__(self, tmp: Path, deploy: Path, env: dict[str, str], *extra: str) -> None:
        self.out = tmp / "boot.out"
        self.env = env
        self.tmp = tmp
        with open(self.out, "w") as fh:
            self.proc = subprocess.Popen(rbnx_cmd() + ["boot", "-f", str(deploy), "--log-dir", str(tmp / "logs"),
                                                       "--term-timeout", "10", *extra],
                                         env=env, cwd=tmp, stdout=fh, stderr=subprocess.STDOUT)

    def text(self) -> str:
        return self.out.read_text()

    def wait_text(self, needle: str, timeout: float = 120.0) -> None:
        def seen() -> bool:
            if self.proc.poll() is not None and needle not in self.text():
                raise AssertionError(f"rbnx boot exited {self.proc.returncode}:\n{self.text()}")
            return needle in self.text()

        wait_until(seen, timeout, f"{needle!r} in boot output")

    def state(self) -> dict[str, Any]:
        files = list((self.tmp / "state").glob("boot-*.json"))
        assert len(files) == 1, files
        return json.loads(files[0].read_text())

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(30)


def recorded(st: dict[str, Any]) -> tuple[list[int], list[int]]:
    pids = [st["pid"], st["atlas_proc"]["pid"], *(c["pid"] for c in st["children"])]
    pgids = [st["atlas_proc"]["pgid"], *(c["pgid"] for c in st["children"])]
    return pids, pgids


def all_gone(pids: list[int], pgids: list[int]) -> bool:
    return not any(alive(p) for p in pids) and not any(group_alive(g) for g in pgids)


@pytest.fixture
def minimal(tmp_path: Path) -> tuple[Path, dict[str, str]]:
    return copy_minimal(tmp_path) / "deploy.yaml", make_env(tmp_path)


def test_boot_defers_retries_caps_and_sigint_leaves_nothing(tmp_path: Path, minimal: tuple[Path, dict]) -> None:
    deploy, env = minimal
    # --serial: B starts alone, so it must answer Deferred (in parallel A may already be up when B asks)
    boot = Boot(tmp_path, deploy, env, "--serial")
    try:
        boot.wait_text(SUMMARY)
        out = boot.text()
        assert "odom_consumer (service): deferred(waiting for robonix/primitive/chassis/odom)" in out
        # B was started first, deferred, and became active only after A.
        assert out.index("odom_consumer (service): starting") < out.index("odom_primitive (primitive): starting")
        assert out.index("odom_primitive (primitive): active") < out.index("odom_consumer (service): active")
        st = boot.state()
        atlas = st["atlas"]
        assert atlas.startswith("127.0.0.1:")

        caps = run(["--atlas", atlas, "caps", "--json"], env, tmp_path)
        assert caps.returncode == 0, caps.stderr
        provs = {p["id"]: p for p in json.loads(caps.stdout)}
        assert set(provs) == {"odom_consumer", "odom_primitive"}
        assert all(p["state"] == "STATE_ACTIVE" for p in provs.values())
        contracts = {p: {c["contract_id"] for c in provs[p]["capabilities"]} for p in provs}
        assert contracts["odom_primitive"] == {"robonix/lifecycle/driver", "robonix/primitive/chassis/driver",
                                               "robonix/primitive/chassis/odom"}
        assert "robonix/lifecycle/driver" in contracts["odom_consumer"]

        text = run(["--atlas", atlas, "caps", "-v"], env, tmp_path)
        assert "odom_primitive  [primitive]  active" in text.stdout
        assert "robonix/primitive/chassis/odom" in text.stdout
        assert "/odom" in text.stdout
        desc = run(["--atlas", atlas, "describe", "--provider", "odom_consumer"], env, tmp_path)
        assert desc.returncode == 0
        assert "Deferred" in desc.stdout
        assert run(["--atlas", atlas, "inspect"], env, tmp_path).returncode == 0
        assert run(["--atlas", atlas, "contracts", "--prefix", "robonix/primitive/chassis"],
                   env, tmp_path).stdout.count("robonix/primitive/chassis/") >= 2

        pids, pgids = recorded(st)
        assert all(alive(p) for p in pids)
        boot.proc.send_signal(signal.SIGINT)
        assert boot.proc.wait(180) == 0, boot.text()
        wait_until(lambda: all_gone(pids, pgids), 30, "every recorded process to be gone")
        assert "CMD_SHUTDOWN ok" in boot.text()
        assert not list((tmp_path / "state").glob("boot-*.json"))
    finally:
        boot.kill()


def test_rbnx_shutdown_stops_a_running_boot(tmp_path: Path, minimal: tuple[Path, dict]) -> None:
    deploy, env = minimal
    boot = Boot(tmp_path, deploy, env, "--no-progress")
    try:
        boot.wait_text(SUMMARY)
        pids, pgids = recorded(boot.state())
        res = run(["shutdown", "-f", str(deploy)], env, tmp_path, timeout=240)
        assert res.returncode == 0, res.stderr
        assert boot.proc.wait(60) == 0
        wait_until(lambda: all_gone(pids, pgids), 30, "every recorded process to be gone")
    finally:
        boot.kill()


def test_sigkill_of_the_boot_leaves_nothing_behind(tmp_path: Path, minimal: tuple[Path, dict]) -> None:
    """A supervisor killed with SIGKILL cannot run its shutdown; its children must still go away
    (parent-death signal), or every killed boot would leak an atlas and its providers."""
    deploy, env = minimal
    boot = Boot(tmp_path, deploy, env, "--no-progress")
    try:
        boot.wait_text(SUMMARY)
        pids, pgids = recorded(boot.state())
        assert all(alive(p) for p in pids[1:])
        boot.proc.send_signal(signal.SIGKILL)
        boot.proc.wait(30)
        wait_until(lambda: all_gone(pids, pgids), 60, "every recorded process to be gone after SIGKILL of rbnx")
    finally:
        boot.kill()


def test_exit_after_boot_then_shutdown_from_state_file(tmp_path: Path, minimal: tuple[Path, dict]) -> None:
    deploy, env = minimal
    # A fixed port: the deployment is (file, atlas address), so a second boot of it must be refused.
    # (With port 0 every boot is a deployment of its own.)
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        env = dict(env, RBNX_ATLAS_LISTEN=f"127.0.0.1:{s.getsockname()[1]}")
    res = run(["boot", "-f", str(deploy), "--log-dir", str(tmp_path / "logs"), "--no-progress",
               "--exit-after-boot"], env, tmp_path, timeout=240)
    st = json.loads(next((tmp_path / "state").glob("boot-*.json")).read_text())
    pids, pgids = recorded(st)
    try:
        assert res.returncode == 0, res.stdout + res.stderr
        assert SUMMARY in res.stdout
        assert all(alive(p) for p in pids[1:])
        again = run(["boot", "-f", str(deploy), "--no-progress"], env, tmp_path, timeout=60)
        assert again.returncode == 1
        assert "already booted by a previous boot" in again.stderr
    finally:
        down = run(["shutdown", "-f", str(deploy), "--term-timeout", "10"], env, tmp_path, timeout=240)
        assert down.returncode == 0, down.stderr
        wait_until(lambda: all_gone(pids, pgids), 30, "every recorded process to be gone")


def test_failures_are_reported_and_boot_carries_on(tmp_path: Path) -> None:
    root = copy_minimal(tmp_path)
    broken = root / "broken"
    broken.mkdir()
    (broken / "package_manifest.yaml").write_text(
        "manifestVersion: 1\npackage: {name: broken, version: '1', description: d, license: MIT}\n"
        "start: echo 'cannot open device /dev/null0' >&2; exit 3\n")
    (root / "deploy.yaml").write_text(
        "manifestVersion: 1\nname: failing\nsystem: {atlas: {listen: '127.0.0.1:0'}}\n"
        "service:\n  - {name: lonely, path: odom_consumer}\n  - {name: broken, path: broken}\n")
    env = make_env(tmp_path)
    boot = Boot(tmp_path, root / "deploy.yaml", env, "--boot-timeout", "4", "--no-progress")
    try:
        boot.wait_text("failures:", timeout=180)
        boot.wait_text("broken (service)")
        out = boot.text()
        assert "boot: 0/2 entries ready" in out
        assert "lonely (service): still deferred at the boot deadline: waiting for robonix/primitive/chassis/odom" \
            in out
        assert "broken (service): process exited with code 3" in out
        assert "| cannot open device /dev/null0" in out
        pids, pgids = recorded(boot.state())
        boot.proc.send_signal(signal.SIGTERM)
        assert boot.proc.wait(180) == 1
        wait_until(lambda: all_gone(pids, pgids), 30, "every recorded process to be gone")
    finally:
        boot.kill()


def test_malformed_deploy_exit_2_nothing_started(tmp_path: Path, minimal: tuple[Path, dict]) -> None:
    deploy, env = minimal
    bad = deploy.with_name("bad.yaml")
    bad.write_text("manifestVersion: 1\nname: bad\nservice:\n  - name: x\n    path: odom_consumer\n"
                   "  - name: x\n    path: nowhere\n  - path: odom_primitive\n    url: https://e/x.git\n")
    res = run(["boot", "-f", str(bad), "--log-dir", str(tmp_path / "logs")], env, tmp_path)
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert lines == [
        f"{bad}: service[2]: exactly one of 'path' or 'url' must be set",
        f"{bad}: service[2].name: missing required key",
    ]
    assert "Traceback" not in res.stderr
    assert not (tmp_path / "logs").exists()
    bad.write_text("manifestVersion: 1\nname: bad\nservice:\n  - name: x\n    path: odom_consumer\n"
                   "  - name: x\n    path: nowhere\n")
    res = run(["boot", "-f", str(bad), "--log-dir", str(tmp_path / "logs")], env, tmp_path)
    assert res.returncode == 2
    assert res.stderr.strip().splitlines() == [
        f"{bad}: service[1].name: duplicate name 'x' (first used by service[0])"]
    bad.write_text("name: [unclosed\n")
    res = run(["boot", "-f", str(bad)], env, tmp_path)
    assert res.returncode == 2
    assert len(res.stderr.strip().splitlines()) == 1
    assert res.stderr.startswith(f"{bad}:2:")
    assert not (tmp_path / "logs").exists()
    assert not (tmp_path / "state").exists()


def test_busy_atlas_port_fails_clearly(tmp_path: Path, minimal: tuple[Path, dict]) -> None:
    deploy, env = minimal
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen(1)
        port = s.getsockname()[1]
        env = dict(env, RBNX_ATLAS_LISTEN=f"127.0.0.1:{port}")
        res = run(["boot", "-f", str(deploy), "--log-dir", str(tmp_path / "logs")], env, tmp_path)
    assert res.returncode == 1
    assert f"something already listens on 127.0.0.1:{port}" in res.stderr
    assert not (tmp_path / "logs" / "odom_consumer.log").exists()


def test_atlas_unreachable_is_one_line(tmp_path: Path) -> None:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    res = run(["--atlas", f"127.0.0.1:{port}", "caps"], make_env(tmp_path), tmp_path)
    assert res.returncode == 1
    assert res.stderr.strip().count("\n") == 0
    assert "cannot reach" in res.stderr


def test_sigint_while_deferred_stops_everything(tmp_path: Path) -> None:
    root = copy_minimal(tmp_path)
    (root / "deploy.yaml").write_text(
        "manifestVersion: 1\nname: waiting\nsystem: {atlas: {listen: '127.0.0.1:0'}}\n"
        "service:\n  - {name: lonely, path: odom_consumer}\n")
    boot = Boot(tmp_path, root / "deploy.yaml", make_env(tmp_path))
    try:
        boot.wait_text("lonely (service): deferred(")
        pids, pgids = recorded(boot.state())
        boot.proc.send_signal(signal.SIGINT)
        assert boot.proc.wait(180) == 130
        assert "interrupted" in boot.text()
        wait_until(lambda: all_gone(pids, pgids), 30, "every recorded process to be gone")
    finally:
        boot.kill()


def test_start_one_package_against_running_atlas(tmp_path: Path, minimal: tuple[Path, dict]) -> None:
    """`rbnx start -p` adds a package to a booted system; -s overrides reach CMD_INIT."""
    deploy, env = minimal
    boot = Boot(tmp_path, deploy, env, "--no-progress")
    start = None
    try:
        boot.wait_text(SUMMARY)
        atlas = boot.state()["atlas"]
        out = tmp_path / "start.out"
        with open(out, "w") as fh:
            args = ["--atlas", atlas, "start", "-p", str(deploy.parent / "odom_primitive"), "--name", "odom_extra",
                    "--kind", "primitive", "-s", "topic=/odom2", "--log-dir", str(tmp_path / "startlogs"),
                    "--no-progress"]
            start = subprocess.Popen(rbnx_cmd() + args, env=env, cwd=tmp_path, stdout=fh, stderr=subprocess.STDOUT)
        wait_until(lambda: "odom_extra is active" in out.read_text(), 120, "rbnx start to report active")
        caps = json.loads(run(["--atlas", atlas, "caps", "--json", "-v", "--id", "odom_extra"], env, tmp_path).stdout)
        odom = [c for c in caps[0]["capabilities"] if c["contract_id"] == "robonix/primitive/chassis/odom"]
        assert odom[0]["endpoint"] == "/odom2"
        start.send_signal(signal.SIGINT)
        assert start.wait(120) == 0
        boot.proc.send_signal(signal.SIGINT)
        assert boot.proc.wait(180) == 0
    finally:
        if start is not None and start.poll() is None:
            start.kill()
        boot.kill()


def test_refused_cmd_init_stops_the_boot_exit_2(tmp_path: Path) -> None:
    """A provider answering Err to CMD_INIT (its config refused) is final: rbnx boot does not wait out the
    boot deadline; it names the entry and the field, stops everything it started and exits 2."""
    root = copy_minimal(tmp_path)
    prim = root / "odom_primitive" / "provider_odom.py"
    prim.write_text(prim.read_text().replace(
        "from robonix_api import Ok, Primitive", "from robonix_api import Err, Ok, Primitive").replace(
        "def init(cfg: dict) -> Ok:\n",
        "def init(cfg: dict) -> Ok:\n    if not str(cfg.get('topic', '/')).startswith('/'):\n"
        "        return Err(f\"topic: must start with '/', got {cfg['topic']!r}\")\n"))
    deploy = root / "deploy.yaml"
    deploy.write_text(deploy.read_text().replace("topic: /odom", "topic: odom"))
    boot = Boot(tmp_path, deploy, make_env(tmp_path), "--boot-timeout", "3600", "--no-progress")
    try:
        code = boot.proc.wait(600)  # waiting like for a Deferred would last the whole hour
        out = boot.text()
        assert code == 2, out
        assert "rbnx boot: primitive[0] (odom_primitive): CMD_INIT: topic: must start with '/', got 'odom'" in out
        assert "running;" not in out
        st = json.loads((tmp_path / "logs" / "rbnx-boot.json").read_text())  # the last state rbnx recorded
        assert {c["name"] for c in st["children"]} == {"odom_primitive", "odom_consumer"}
        pids, pgids = recorded(st)
        wait_until(lambda: all_gone(pids, pgids), 30, "every recorded process to be gone")
        assert not list((tmp_path / "state").glob("boot-*.json"))
    finally:
        boot.kill()
