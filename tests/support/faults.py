"""Fault injection into a running ``rbnx boot`` of the sim deploy, shared by tests/faults and
bench/fault_suite.py. No pytest in here.

``SimBoot`` boots ``examples/sim/deploy.yaml`` with the real console script (own state dir, DDS domain and
a fixed free atlas port, so a killed atlas can be started again at the same address), talks to the
providers like any robonix consumer (atlas lookup, then gRPC), and ``Recorder`` samples the simulator's
ground truth and the goal's status in a thread so a fault's effects can be timed afterwards: when the
robot stopped (ground-truth speed < 0.05 m/s, on sim time), when the goal's status changed and to what,
when every provider was ACTIVE again. Everything started here is stopped here, by PID.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import grpc

from robonix_api import auth
from robonix_api.atlas_client import AtlasClient
from robonix_api.procs import stop_process
from robonix_api.proto_gen import navigation_pb2, sim_pb2
from robonix_api.proto_gen import robonix_contracts_pb2_grpc as stubs
from robonix_api.types import LifecycleState

from .procs import alive, wait_until

REPO = Path(__file__).resolve().parents[2]
SIM_DEPLOY = REPO / "examples" / "sim" / "deploy.yaml"
ENTRIES = ("panda_mobile", "mapping", "nav2")
STOPPED_MPS = 0.05
TERMINAL = ("SUCCEEDED", "FAILED", "CANCELED")
NAVIGATE = "robonix/service/navigation/navigate"
STATUS = "robonix/service/navigation/navigate/status"
GROUND_TRUTH = "robonix/primitive/sim/ground_truth"
KITCHEN = {"start": (3.5, 1.6), "island_east": (5.8, 3.0), "pantry": (8.3, 6.8), "dining": (2.5, 6.2),
           "fridge": (8.5, 2.0)}


def rbnx_cmd() -> list[str]:
    exe = Path(sys.executable).parent / "rbnx"
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "rbnx.cli"]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def deploy_copy(tmp: Path, **entries: dict[str, Any]) -> Path:
    """The sim deploy written to ``tmp/deploy.yaml`` with absolute package paths and per-entry keys
    merged in (e.g. ``mapping={"restart": "never"}``: a killed provider then stays dead)."""
    import yaml

    doc = yaml.safe_load(SIM_DEPLOY.read_text())
    for section in ("primitive", "service", "skill"):
        for e in doc.get(section) or []:
            if e.get("path"):
                e["path"] = str((SIM_DEPLOY.parent / e["path"]).resolve())
            e.update(entries.get(e["name"], {}))
    out = tmp / "deploy.yaml"
    out.write_text(yaml.safe_dump(doc, sort_keys=False))
    return out


def atlas_cmd(listen: str) -> list[str]:
    exe = Path(sys.executable).parent / "robonix-atlas"
    return [str(exe), "--listen", listen] if exe.exists() else [sys.executable, "-m", "atlas.server",
                                                                  "--listen", listen]


class SimBoot:
    """``rbnx boot`` of the sim deploy in ``tmp``; a context manager that never leaves a process behind."""

    def __init__(self, tmp: Path, scene: str = "kitchen", rtf: str = "1", env: dict[str, str] | None = None,
                 boot_timeout_s: float = 180.0, deploy: Path = SIM_DEPLOY) -> None:
        from rbnx.demo.boot import pick_domain_id

        self.tmp, self.deploy = tmp, deploy
        self.listen = f"127.0.0.1:{free_port()}"
        self.env = dict(os.environ, RBNX_STATE_DIR=str(tmp / "state"), RBNX_ATLAS_LISTEN=self.listen,
                        RBNX_SIM_SCENE=scene, RBNX_SIM_RTF=rtf, PYTHONUNBUFFERED="1",
                        ROS_DOMAIN_ID=str(pick_domain_id()), **(env or {}))
        for name in ("ROBONIX_ATLAS", "RBNX_INSTANCE_NAME", "RBNX_DEPLOY_MANAGED"):
            self.env.pop(name, None)
        self.out = tmp / "boot.out"
        self.seen: dict[int, str] = {}          # every PID ever recorded (name): for the orphan count
        self.own_atlas: subprocess.Popen | None = None
        self.token = ""
        self._channels: dict[str, grpc.Channel] = {}
        with open(self.out, "w") as fh:
            self.proc = subprocess.Popen(rbnx_cmd() + ["boot", "-f", str(deploy), "--no-progress",
                                                       "--log-dir", str(tmp / "logs")],
                                         env=self.env, cwd=tmp, stdout=fh, stderr=subprocess.STDOUT,
                                         stdin=subprocess.DEVNULL)
        try:
            wait_until(self._booted, boot_timeout_s, "the boot summary (3/3 entries ready)", 0.2)
            self.pids()
            # The deployment token (rbnx boot draws one per boot): our clients send it from the environment.
            self.token = str(self.state().get("token") or "")
            if self.token:
                os.environ[auth.TOKEN_ENV] = self.token
        except BaseException:
            self.close()
            raise

    def _booted(self) -> bool:
        if self.proc.poll() is not None:
            raise AssertionError(f"rbnx boot exited {self.proc.returncode}:\n{self.out.read_text()[-3000:]}")
        return f"{len(ENTRIES)}/{len(ENTRIES)} entries ready" in self.out.read_text()

    @property
    def atlas(self) -> str:
        return self.listen

    # ---- processes ---------------------------------------------------------------------------------
    def state(self) -> dict[str, Any]:
        (f,) = (self.tmp / "state").glob("boot-*.json")
        return json.loads(f.read_text())

    def pids(self) -> dict[str, int]:
        """Current PID per entry (and ``atlas``) from the boot's state file; remembered for orphans."""
        try:
            st = self.state()
        except (ValueError, OSError):
            return {}
        out = {c["name"]: int(c["pid"]) for c in st.get("children") or []}
        if st.get("atlas_proc"):
            out["atlas"] = int(st["atlas_proc"]["pid"])
        for c in st.get("children") or []:
            for p, _t in c.get("extra_pids") or []:
                self.seen[int(p)] = c["name"]
        if self.own_atlas is not None:
            out["atlas"] = self.own_atlas.pid
        for name, pid in out.items():
            self.seen[pid] = name
        return out

    def atlas_listening(self) -> bool:
        host, _, port = self.listen.rpartition(":")
        try:
            with socket.create_connection((host, int(port)), timeout=0.5):
                return True
        except OSError:
            return False

    def ensure_atlas(self, wait_s: float = 5.0) -> str:
        """After the atlas was killed: give the boot ``wait_s`` to start it again (``restart:
        on-failure``), else start one ourselves. Returns who did: "rbnx boot" or "fault suite"."""
        deadline = time.monotonic() + wait_s
        while time.monotonic() < deadline:
            if self.atlas_listening():
                self.pids()
                return "rbnx boot"
            time.sleep(0.1)
        self.restart_atlas()
        return "fault suite"

    def restart_atlas(self) -> None:
        """Start an atlas at the same address and with the deployment's token (what a supervisor would do),
        in its own session."""
        env = dict(self.env, **({auth.TOKEN_ENV: self.token} if self.token else {}))
        with open(self.tmp / "logs" / "atlas-restarted.log", "a") as log:  # the child keeps its own copy
            self.own_atlas = subprocess.Popen(atlas_cmd(self.listen), env=env, stdout=log, stderr=subprocess.STDOUT,
                                              stdin=subprocess.DEVNULL, start_new_session=True)
        self.seen[self.own_atlas.pid] = "atlas (restarted)"

    def states(self) -> dict[str, str]:
        """Provider id -> lifecycle state name on the atlas ({} when the atlas does not answer)."""
        try:
            with AtlasClient(self.atlas) as c:
                c.timeout = 2.0
                return {p.id: LifecycleState(p.state).name for p in c.query() if p.id in ENTRIES}
        except Exception:
            return {}

    def all_active(self) -> bool:
        return self.states() == dict.fromkeys(ENTRIES, "ACTIVE")

    # ---- contracts (endpoints cached: they keep working while the atlas is down) --------------------
    def _channel(self, contract: str, fresh: bool = False) -> grpc.Channel:
        if fresh or contract not in self._channels:
            with AtlasClient(self.atlas) as c:
                c.timeout = 2.0
                cap = c.find_unique_capability(contract_id=contract, transport="grpc")
                with c.connect_capability(consumer_id="fault-suite", provider_id=cap.provider_id,
                                          contract_id=contract, transport="grpc") as ch:
                    ep = ch.endpoint.removeprefix("grpc://")
            old = self._channels.pop(contract, None)
            if old is not None:
                old.close()
            self._channels[contract] = auth.channel(ep)
        return self._channels[contract]

    def _call(self, contract: str, fn: Any) -> Any:
        try:
            return fn(self._channel(contract))
        except grpc.RpcError as exc:
            if exc.code() != grpc.StatusCode.UNAVAILABLE:
                raise
            return fn(self._channel(contract, fresh=True))  # provider restarted: look it up again

    def navigate(self, x: float, y: float) -> str:
        req = navigation_pb2.Navigate_Request()
        req.goal.header.frame_id = "map"
        req.goal.pose.position.x, req.goal.pose.position.y = x, y
        req.goal.pose.orientation.w = 1.0
        resp = self._call(NAVIGATE, lambda ch: stubs.RobonixServiceNavigationNavigateStub(ch).Navigate(req,
                                                                                                      timeout=10))
        if not resp.accepted:
            raise AssertionError(f"goal ({x}, {y}) not accepted: {resp.detail}")
        return resp.run_id

    def status(self, run_id: str) -> tuple[str, str]:
        req = navigation_pb2.GetNavigationStatus_Request(run_id=run_id)
        st = self._call(STATUS, lambda ch: stubs.RobonixServiceNavigationNavigateStatusStub(ch)
                        .GetNavigationStatus(req, timeout=2))
        return st.state, st.detail

    def ground_truth(self) -> Any:
        req = sim_pb2.GetGroundTruth_Request()
        return self._call(GROUND_TRUTH, lambda ch: stubs.RobonixPrimitiveSimGroundTruthStub(ch)
                          .GetGroundTruth(req, timeout=1))

    def wait_terminal(self, run_id: str, timeout_s: float) -> tuple[str, str]:
        def done() -> tuple[str, str] | None:
            try:
                st = self.status(run_id)
            except Exception:
                return None
            return st if st[0] in TERMINAL else None

        return wait_until(done, timeout_s, f"goal {run_id} to finish", 0.25)

    # ---- teardown ----------------------------------------------------------------------------------
    def shutdown(self, timeout_s: float = 120.0) -> list[str]:
        """``rbnx shutdown -f`` (a terminal's way), wait for rbnx boot; the recorded PIDs still alive after.

        An atlas this helper restarted is not rbnx's to stop: it is stopped here and not counted.
        """
        self.pids()
        subprocess.run(rbnx_cmd() + ["shutdown", "-f", str(self.deploy)], env=self.env, cwd=self.tmp,
                       capture_output=True, text=True, timeout=timeout_s, stdin=subprocess.DEVNULL)
        with contextlib.suppress(subprocess.TimeoutExpired):
            self.proc.wait(timeout_s)
        own = self.own_atlas.pid if self.own_atlas is not None else None
        self._stop_own_atlas()
        deadline = time.monotonic() + 30
        left = [pid for pid in self.seen if pid != own and alive(pid)]
        while left and time.monotonic() < deadline:
            time.sleep(0.2)
            left = [pid for pid in left if alive(pid)]
        return [f"{self.seen[p]} (pid {p})" for p in left]

    def _stop_own_atlas(self) -> None:
        a, self.own_atlas = self.own_atlas, None
        if a is not None:
            stop_process(a, 15.0, kill_timeout=15.0)

    def close(self) -> None:
        """Last resort (a failed test): SIGCONT + SIGKILL every recorded process, by PID."""
        if self.token and os.environ.get(auth.TOKEN_ENV) == self.token:
            os.environ.pop(auth.TOKEN_ENV, None)
        for ch in self._channels.values():
            ch.close()
        self._channels.clear()
        self.pids()
        stop_process(self.proc, 60.0, kill_timeout=30.0, first=signal.SIGINT)   # Ctrl-C is its clean stop
        self._stop_own_atlas()
        for pid in self.seen:
            if alive(pid):
                for sig in (signal.SIGCONT, signal.SIGKILL):
                    with contextlib.suppress(ProcessLookupError):
                        os.kill(pid, sig)

    def __enter__(self) -> SimBoot:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


@dataclass
class Sample:
    """One observation: ground truth (``sim``/``speed`` set) or the goal's status (``state`` set)."""

    wall: float                      # when it was answered (monotonic)
    sim: float | None = None         # ground truth's sim time
    speed: float | None = None
    state: str = ""
    detail: str = ""


@dataclass
class Recorder:
    """Samples ground truth and one goal's status every ``period_s`` (wall), each in its own thread, so a
    frozen navigation process (status calls hanging) does not blind the ground truth, nor the reverse."""

    boot: SimBoot
    run_id: str
    period_s: float = 0.05
    samples: list[Sample] = field(default_factory=list)
    _stop: threading.Event = field(default_factory=threading.Event)
    _threads: list[threading.Thread] = field(default_factory=list)

    def start(self) -> Recorder:
        for fn in (self._ground_truth, self._status):
            t = threading.Thread(target=self._every, args=(fn,), name="fault-recorder", daemon=True)
            t.start()
            self._threads.append(t)
        return self

    def stop(self) -> None:
        self._stop.set()
        for t in self._threads:
            t.join(10)

    def _every(self, fn: Any) -> None:
        while not self._stop.is_set():
            try:
                s = fn()
                s.wall = time.monotonic()
                self.samples.append(s)
            except Exception:
                pass
            self._stop.wait(self.period_s)

    def _ground_truth(self) -> Sample:
        gt = self.boot.ground_truth()
        return Sample(0.0, sim=gt.sim_time, speed=math.hypot(gt.vx, gt.vy))

    def _status(self) -> Sample:
        state, detail = self.boot.status(self.run_id)
        return Sample(0.0, state=state, detail=detail)

    def _gt(self) -> list[Sample]:
        return [s for s in list(self.samples) if s.speed is not None]

    def _st(self) -> list[Sample]:
        return [s for s in list(self.samples) if s.state]

    def latest(self) -> tuple[Sample | None, Sample | None]:
        """(latest ground truth, latest status)."""
        gt, st = self._gt(), self._st()
        return (gt[-1] if gt else None), (st[-1] if st else None)

    def moving(self, min_speed: float = 0.1) -> bool:
        gt, st = self.latest()
        return gt is not None and st is not None and gt.speed > min_speed and st.state == "RUNNING"

    def sim_at(self, wall: float) -> float | None:
        """Sim time of the last ground-truth sample at or before ``wall``."""
        sims = [s.sim for s in self._gt() if s.wall <= wall]
        return sims[-1] if sims else None

    def stopped_after(self, wall: float, within_s: float = math.inf) -> tuple[float, float] | None:
        """(sim s, wall s) from ``wall`` to the first ground-truth speed below 0.05 m/s (looking no further
        than ``within_s`` wall seconds), or None."""
        t_sim = self.sim_at(wall)
        for s in self._gt():
            if s.wall > wall + within_s:
                break
            if s.wall > wall and s.speed < STOPPED_MPS:
                return (s.sim - t_sim if t_sim is not None else math.nan), s.wall - wall
        return None

    def status_change_after(self, wall: float) -> tuple[float, str, str] | None:
        """(wall s, state, detail) of the first status after ``wall`` that reports the fault: a new state,
        or a RUNNING detail that says it waits / is paused."""
        st = self._st()
        before = [s for s in st if s.wall <= wall]
        prev = before[-1].state if before else "RUNNING"
        for s in st:
            if s.wall > wall and (s.state != prev or "waiting for" in s.detail or "paused" in s.detail):
                return s.wall - wall, s.state, s.detail
        return None


def occupied_iou(a: Any, b: Any) -> float:
    """IoU of the occupied cells (>= 65) of two grids of one resolution, compared in world cells."""
    import numpy as np

    assert math.isclose(a.resolution, b.resolution), (a.resolution, b.resolution)

    def cells(g: Any) -> set[tuple[int, int]]:
        rows, cols = np.nonzero(g.data >= 65)
        ox, oy = round(g.origin_x / g.resolution), round(g.origin_y / g.resolution)
        return set(zip((cols + ox).tolist(), (rows + oy).tolist(), strict=True))

    ca, cb = cells(a), cells(b)
    return len(ca & cb) / max(1, len(ca | cb))


def signal_pid(pid: int, sig: int) -> None:
    with contextlib.suppress(ProcessLookupError):
        os.kill(pid, sig)
