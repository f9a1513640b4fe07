"""The replay round trip, shared by its test and its benchmark: boot a fresh slam_service (mapping mode,
``use_sim_time``, inputs by ``topic_remap``: no HAL on the atlas), `rbnx replay` a live recording into it
(without the live run's map->odom) while `rbnx record` keeps what the new SLAM publishes, then score the
two runs with rbnx.replay_eval. No pytest in here (the bench uses it)."""

from __future__ import annotations

import json
import signal
import subprocess
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from .boot import RbnxBoot, rbnx_cmd
from .procs import wait_until

REPO = Path(__file__).resolve().parents[2]
REPLAY_DEPLOY = """\
manifestVersion: 1
name: replay-mapping
system:
  atlas:
    listen: ${{RBNX_ATLAS_LISTEN:-127.0.0.1:0}}
service:
  - name: mapping
    path: {slam}
    config:
      mode: mapping
      use_sim_time: true            # the recording's /clock
      topic_remap:
        scan: /scan
        odom: /odom
"""
REPLAY_TOPICS = ["/scan", "/odom", "/tf", "/tf_static", "/clock"]


def _slam_idle(boot: RbnxBoot) -> Callable[[], bool]:
    """A predicate: SLAM's status says idle (every scan received dealt with, its map on /map) on two polls in a
    row with no scan received in between, so scans the replay sent just before it exited are counted too."""
    from robonix_api import auth
    from robonix_api.atlas_client import AtlasClient
    from robonix_api.proto_gen import map_pb2
    from robonix_api.proto_gen import robonix_contracts_pb2_grpc as stubs

    from .e2e import grpc_endpoint

    with AtlasClient(boot.state()["atlas"]) as client:
        endpoint = grpc_endpoint(client, "robonix/service/map/get_mode")
    last: list[int] = []

    def idle() -> bool:
        with auth.channel(endpoint) as ch:
            reply = stubs.RobonixServiceMapGetModeStub(ch).GetMode(map_pb2.GetMode_Request(), timeout=30)
        st = json.loads(reply.detail)
        received = int(st.get("scans_received", 0))
        settled = bool(st["idle"]) and last == [received]
        last[:] = [received] if st["idle"] else []
        return settled

    return idle


def replay_into_fresh_slam(live_mcap: Path, tmp: Path, rate: float = 1.0) -> tuple[Path, dict[str, Any]]:
    """(the replay session's recording, timings); every process started here is stopped here."""
    tmp.mkdir(parents=True, exist_ok=True)
    deploy = tmp / "replay_deploy.yaml"
    deploy.write_text(REPLAY_DEPLOY.format(slam=REPO / "slam_service"))
    out = tmp / "replay_session.mcap"
    info: dict[str, Any] = {}
    with RbnxBoot(deploy, tmp) as boot:
        try:
            boot.wait_ready(1, 180)
            rec_log = open(tmp / "record.out", "w")  # noqa: SIM115 - closed below
            rec = subprocess.Popen(rbnx_cmd() + ["record", "-o", str(out), "-q", "/map", "/tf"],
                                   stdout=rec_log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
            try:
                wait_until(lambda: "recording" in (tmp / "record.out").read_text() or rec.poll() is not None,
                           60, "rbnx record to start")
                t0 = time.monotonic()
                r = subprocess.run(rbnx_cmd() + ["replay", str(live_mcap), "--rate", f"{rate:g}", "--drop-tf", "odom",
                                                 "--delay", "2", "--topics", *REPLAY_TOPICS],
                                   capture_output=True, text=True, timeout=1800, stdin=subprocess.DEVNULL)
                info["replay_wall_s"] = time.monotonic() - t0
                info["replay_output"] = r.stdout.strip().splitlines()[-1:] + r.stderr.strip().splitlines()[-3:]
                if r.returncode != 0:
                    raise AssertionError(f"rbnx replay exited {r.returncode}: {r.stdout}{r.stderr}")
                # SLAM works off its scan queue and republishes /map when it changed: wait until it has.
                wait_until(_slam_idle(boot), 120, "SLAM to work off the replayed scans and publish its map", 0.2)
            finally:
                rec.send_signal(signal.SIGINT)
                rc = rec.wait(60)
                rec_log.close()
            if rc != 0:
                raise AssertionError(f"rbnx record exited {rc}: {(tmp / 'record.out').read_text()}")
        finally:
            boot.interrupt()
            boot.wait_all_exited()
    return out, info
