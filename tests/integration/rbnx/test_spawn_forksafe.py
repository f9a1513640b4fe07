"""Starting children while gRPC channels are open never aborts them (gRPC's fork handlers stay off).

With gRPC fork support on, a fork+exec with a preexec function (rbnx's parent-death signal) restarted
gRPC's poller in the child, whose close_fds then closed the poller's epoll fd: the child aborted with
``epoll_wait error: Bad file descriptor`` (rc -6) in about 4 % of spawns. The script below runs in a fresh
interpreter so that only what ``import rbnx`` sets is in force.
"""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

SCRIPT = r"""
import sys, threading, time
from pathlib import Path
import rbnx.boot.procs as procs  # rbnx's package import must switch gRPC fork support off
import grpc
from atlas.server import AtlasServer
from robonix_api.proto_gen import atlas_pb2, atlas_pb2_grpc

srv = AtlasServer(listen="127.0.0.1:0")
addr = srv.start()
stop = threading.Event()

def idle_client():  # a live channel whose poller is mostly idle: the case that crashed
    stub = atlas_pb2_grpc.AtlasStub(grpc.insecure_channel(addr))
    while not stop.is_set():
        stub.ListContracts(atlas_pb2.ListContractsRequest(namespace_prefix="robonix/x"))
        time.sleep(0.05)

for _ in range(2):
    threading.Thread(target=idle_client, daemon=True).start()
procs.set_supervised(True)  # children get the parent-death signal, as under rbnx boot
if sys.argv[2] == "preexec":  # the fallback where util-linux setpriv is missing: a real fork()
    procs._SETPRIV = None
n, bad = int(sys.argv[1]), []
for i in range(n):
    g = procs.spawn(f"child{i}", ["/bin/true"], Path("."), {}, None)
    rc = g.popen.wait(timeout=60)
    if rc != 0:
        bad.append(rc)
stop.set()
srv.stop(0)
print(f"spawned {n}, failed {len(bad)} {bad[:5]}")
"""


@pytest.mark.parametrize("how", ["setpriv", "preexec"])
def test_spawn_under_open_grpc_channels_never_aborts_the_child(how: str) -> None:
    """Both ways rbnx sets the parent-death signal: setpriv after vfork+exec, or a preexec hook after fork()."""
    env = {k: v for k, v in os.environ.items() if k != "GRPC_ENABLE_FORK_SUPPORT"}
    res = subprocess.run([sys.executable, "-c", SCRIPT, "200", how], capture_output=True, text=True, timeout=300,
                         env=env)
    assert res.returncode == 0, res.stderr[-2000:]
    assert "spawned 200, failed 0" in res.stdout, res.stdout + res.stderr[-2000:]
