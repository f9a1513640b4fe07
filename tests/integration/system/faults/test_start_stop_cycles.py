"""Issue 16: starting and stopping a provider 100 times never aborts it.

The abort seen before ("epoll_wait error: Bad file descriptor", rc -6, at start) came from gRPC's fork
handlers: rbnx held gRPC channels while it fork()ed providers, the handlers restarted gRPC's poller in
the child, and the child's close_fds closed the poller's epoll descriptor before exec. Now rbnx spawns
through ``setpriv --pdeathsig`` (vfork + exec, no fork handlers run) and gRPC fork support is off in rbnx
and in every provider (robonix_api.forksafe), so nothing of gRPC runs between fork and exec.

This test does what `rbnx boot` does, 100 times, with the parent busy on gRPC meanwhile: an atlas and
two clients hammering it in this process, a real provider spawned by rbnx's own ``spawn`` (parent-death
signal on, as under boot), registered, driven through CMD_INIT on its gRPC Driver, then stopped with
SIGTERM. Every run must exit 0 with no gRPC abort in its log. Two providers run at a time to keep it
well under two minutes on a loaded 2-core machine.
"""

from __future__ import annotations

import os
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import grpc
import pytest
from support.procs import wait_until

import rbnx.boot.procs as procs
from atlas.server import AtlasServer
from rbnx.atlas_rpc import CMD, Atlas, Driver, driver_capability
from robonix_api.proto_gen import atlas_pb2, atlas_pb2_grpc

pytestmark = [pytest.mark.integration, pytest.mark.slow, pytest.mark.timeout(300)]

REPO = Path(__file__).resolve().parents[4]
PROVIDER = REPO / "examples" / "minimal" / "odom_primitive"
CYCLES = int(os.environ.get("RBNX_TEST_CYCLES", "100"))
ABORT_MARKS = ("epoll_wait", "Bad file descriptor", "Fatal Python error", "Segmentation fault")


def _cycle(i: int, addr: str, tmp: Path) -> tuple[int, str]:
    """One start → registered → CMD_INIT → SIGTERM → exit; returns (exit code, problem or "")."""
    name = f"odom_{i}"
    log = tmp / f"{name}.log"
    env = dict(os.environ, ROBONIX_ATLAS=addr, RBNX_INSTANCE_NAME=name, PYTHONUNBUFFERED="1",
               ROBONIX_HEARTBEAT_PERIOD_S="30")
    group = procs.spawn(name, ["python", "-c", _RUN.format(name=name)], PROVIDER, env, log)
    try:
        with Atlas(addr, timeout=5.0) as atlas:
            def registered() -> atlas_pb2.CapabilityProvider | None:
                prov = atlas.provider(name)
                if prov is None and not group.running():
                    _exited(group)
                return prov if prov is not None and driver_capability(prov) else None

            prov = wait_until(registered, 60, f"{name} to register its Driver", 0.02)
            endpoint, params = atlas.endpoint(name, driver_capability(prov) or "", 1)
        drv = Driver(endpoint, params)
        try:
            reply = drv.call(CMD.CMD_INIT, {"topic": f"/odom_{i}"}, 30.0)
        finally:
            drv.close()
        if not reply.ok:
            return -1000, f"{name}: CMD_INIT failed: {reply.error}"
        group.signal(15)
        rc = group.popen.wait(30)
    finally:
        group.stop(5.0)
    text = log.read_text(errors="replace")
    bad = next((m for m in ABORT_MARKS if m in text), "")
    return rc, f"{name}: rc {rc}, {bad!r} in its log" if (rc != 0 or bad) else ""


def _exited(group: procs.ProcGroup) -> bool:
    raise AssertionError(f"{group.name} exited with code {group.popen.returncode} before registering:\n"
                         + "\n".join(procs.tail(group.log_path or Path("/dev/null"), 20)))


# the example primitive, under the name this cycle gives it (its file hard-codes one id)
_RUN = ("import runpy, robonix_api; g = runpy.run_path('provider_odom.py', run_name='not_main'); "
        "prim = g['prim']; prim.id = '{name}'; prim.run()")


def test_one_hundred_provider_start_stop_cycles_never_abort(tmp_path: Path) -> None:
    srv = AtlasServer(listen="127.0.0.1:0")
    addr = srv.start()
    stop = threading.Event()

    def busy_client() -> None:  # open channels with traffic in the spawning process, as in rbnx boot
        with grpc.insecure_channel(addr) as ch:
            stub = atlas_pb2_grpc.AtlasStub(ch)
            while not stop.is_set():
                stub.Query(atlas_pb2.QueryRequest(), timeout=5)
                stop.wait(0.02)

    clients = [threading.Thread(target=busy_client, daemon=True) for _ in range(2)]
    for c in clients:
        c.start()
    procs.set_supervised(True)
    t0 = time.monotonic()
    try:
        with ThreadPoolExecutor(2) as pool:
            results = list(pool.map(lambda i: _cycle(i, addr, tmp_path), range(CYCLES)))
    finally:
        procs.set_supervised(False)
        stop.set()
        for c in clients:
            c.join(10)
        srv.stop(0)
    problems = [p for _, p in results if p]
    print(f"{CYCLES} start/stop cycles in {time.monotonic() - t0:.1f}s, {len(problems)} failed")
    assert not problems, problems[:5]
    assert all(rc == 0 for rc, _ in results)
