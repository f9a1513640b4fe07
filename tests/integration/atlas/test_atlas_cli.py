"""The ``robonix-atlas`` console script as a real subprocess: ready line, SIGTERM exit 0, exit 2 on a bad
or busy address. Every process started here is stopped by its PID in a ``finally``."""

from __future__ import annotations

import os
import queue
import shutil
import signal
import socket
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from robonix_api.atlas_client import AtlasClient

SCRIPT = shutil.which("robonix-atlas", path=str(Path(sys.executable).parent)) or shutil.which("robonix-atlas")


def _cmd(*args: str) -> list[str]:
    if SCRIPT:
        return [SCRIPT, *args]
    return [sys.executable, "-m", "atlas.server", *args]


def _env(**extra: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROBONIX_ATLAS")}
    env.update(extra)
    return env


def _stop(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        proc.kill()
    proc.wait(timeout=30)


def _first_line(proc: subprocess.Popen, timeout: float = 60.0) -> str:
    """Read stdout's first line with a deadline (a reader thread; no busy waiting)."""
    q: queue.Queue[str] = queue.Queue()
    threading.Thread(target=lambda: q.put(proc.stdout.readline()), daemon=True).start()
    try:
        return q.get(timeout=timeout)
    except queue.Empty:
        raise AssertionError("robonix-atlas printed no ready line in time") from None


def test_console_script_serves_and_stops_on_sigterm() -> None:
    proc = subprocess.Popen(
        _cmd("--listen", "127.0.0.1:0", "--heartbeat-timeout-ms", "5000", "--eviction-interval-ms", "200"),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=_env(),
    )
    try:
        line = _first_line(proc)
        assert line.startswith("atlas listening on 127.0.0.1:"), line
        address = line.split()[-1]
        client = AtlasClient(address)
        try:
            assert client.register_primitive("cli-probe", "robonix/primitive/chassis") == "cli-probe"
            assert [p.id for p in client.query()] == ["cli-probe"]
            assert len(client.list_contracts()) >= 31
        finally:
            client.close()
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(timeout=30) == 0
    finally:
        _stop(proc)


def _run_fail(*args: str, **env: str) -> subprocess.CompletedProcess:
    return subprocess.run(_cmd(*args), capture_output=True, text=True, timeout=60, env=_env(**env))


def test_busy_port_exits_2_with_one_line() -> None:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        sock.listen()
        port = sock.getsockname()[1]
        res = _run_fail(ROBONIX_ATLAS_LISTEN=f"127.0.0.1:{port}")  # env fallback for --listen
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1, res.stderr
    assert "listen" in lines[0], res.stderr
    assert str(port) in lines[0], res.stderr
    assert res.stdout == ""


@pytest.mark.parametrize("listen", ["127.0.0.1", "127.0.0.1:notaport", "127.0.0.1:70000"])
def test_bad_listen_exits_2(listen: str) -> None:
    res = _run_fail("--listen", listen)
    assert res.returncode == 2
    assert "listen" in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1


def test_config_json_as_robonix_rbnx_passes_it() -> None:
    """robonix's rbnx hands system.atlas over as JSON; a robonix env_logger filter picks the level."""
    cfg = '{"listen": "127.0.0.1:0", "log": "robonix_atlas=debug", "heartbeat_timeout_ms": 4000, "pilot": 1}'
    proc = subprocess.Popen(_cmd("--config-json", cfg), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env=_env(ROBONIX_ATLAS_LISTEN="127.0.0.1:1"))  # the JSON wins over env
    try:
        line = _first_line(proc)
        assert line.startswith("atlas listening on 127.0.0.1:"), line
        client = AtlasClient(line.split()[-1])
        try:
            assert client.register_primitive("json-probe", "robonix/primitive/chassis") == "json-probe"
        finally:
            client.close()
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(timeout=30) == 0
        err = proc.stderr.read()
        assert "DEBUG" in err  # the log filter took effect
        assert "ignoring unknown keys pilot" in err
    finally:
        _stop(proc)


@pytest.mark.parametrize(("cfg", "word"), [
    ("{listen: 1}", "invalid JSON"),
    ("[1]", "JSON object"),
    ('{"heartbeat_timeout_ms": -5}', "heartbeat_timeout_ms"),
    ('{"log": "verbose"}', "log"),
    ("[" * 50_000 + "]" * 50_000, "--config-json"),
])
def test_bad_config_json_exits_2_naming_the_field(cfg: str, word: str) -> None:
    res = _run_fail("--config-json", cfg)
    assert res.returncode == 2, res.stderr
    assert word in res.stderr, res.stderr
    assert len(res.stderr.strip().splitlines()) == 1
    assert "Traceback" not in res.stderr
