"""`rbnx boot`: start the atlas, then every entry in order (Deferred ones parked and retried), show
progress, wait for a signal, and shut everything down in reverse order leaving no process behind.
"""

from __future__ import annotations

import os
import re
import shutil
import signal
import socket
import sys
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from types import FrameType
from typing import Any

from rbnx.atlas_rpc import Atlas
from rbnx.boot import deploytoken, procs
from rbnx.boot.entry import EntryRunner, Timing
from rbnx.boot.notes import NoteWatch
from rbnx.boot.procs import ProcGroup, proc_start_ticks, spawn, tail
from rbnx.boot.progress import ProgressView, Row
from rbnx.boot.statefile import remove_state, state_path, write_state
from rbnx.boot.supervise import Supervisor
from rbnx.models import ResolvedDeploy, ResolvedEntry

READY_RE = re.compile(r"atlas listening on (\S+:\d+)")
ATLAS_READY_TIMEOUT_S = 30.0
SUPERVISE_PERIOD_S = 0.1  # how soon after a process death the atlas hears of it (plus one RPC)
LOG_LEVELS = {"trace", "debug", "info", "warn", "warning", "error", "off"}


class BootError(RuntimeError):
    """A boot-wide failure (e.g. the atlas cannot start); one-line message."""


@dataclass
class BootOptions:
    log_dir: Path
    boot_timeout: float = 120.0
    term_timeout: float = 30.0
    progress: bool = True
    verbose: bool = False
    exit_after_boot: bool = False
    gateway: bool = True  # serve the deployment's MCP gateway (not with exit_after_boot: it lives in rbnx)
    parallel: bool = True  # start every entry at once; False: one at a time (next when settled or parked)
    timing: Timing = field(default_factory=Timing)


# ---------------------------------------------------------------------- atlas


def _split(listen: str) -> tuple[str, int]:
    host, _, port = listen.rpartition(":")
    return host.strip("[]"), int(port)


def client_addr(listen: str) -> str:
    """Where clients connect: a wildcard bind is reached over loopback."""
    host, port = _split(listen)
    if host in ("0.0.0.0", "", "::"):
        host = "127.0.0.1"
    return f"{host}:{port}"


def port_in_use(listen: str) -> bool:
    host, port = _split(client_addr(listen))
    if port == 0:
        return False
    try:
        with socket.create_connection((host, port), timeout=0.5):
            return True
    except OSError:
        return False


def atlas_command(listen: str) -> list[str]:
    """The `robonix-atlas` console script of this interpreter's environment, else from PATH."""
    here = Path(sys.executable).parent / "robonix-atlas"
    exe = str(here) if here.exists() else shutil.which("robonix-atlas")
    if exe:
        return [exe, "--listen", listen]
    return [sys.executable, "-m", "atlas.server", "--listen", listen]


def spawn_atlas(listen: str, env: dict[str, str], log_path: Path, log: str | None, append: bool = False) -> ProcGroup:
    """Start the atlas in its own group (refused when its address is taken); see ``wait_atlas``.

    ``append``: a restart keeps the earlier runs' log (the ready line is then looked for after them)."""
    if port_in_use(listen):
        raise BootError(f"atlas: something already listens on {client_addr(listen)}; stop it or change "
                        "system.atlas.listen")
    env = dict(env)
    if log and log.lower() in LOG_LEVELS:
        env.setdefault("ROBONIX_ATLAS_LOG", log.lower())
    offset = log_path.stat().st_size if append and log_path.exists() else 0
    group = spawn("atlas", atlas_command(listen), Path.cwd(), env, log_path, append=append)
    group.log_offset = offset
    return group


def wait_atlas(group: ProcGroup, log_path: Path, after: int = 0) -> str:
    """Wait for the atlas's ready line (past byte ``after`` of its log); returns the client address
    (BootError, atlas stopped, if none)."""
    deadline = time.monotonic() + ATLAS_READY_TIMEOUT_S
    while time.monotonic() < deadline:
        m = READY_RE.search(log_path.read_bytes()[after:].decode(errors="replace")) if log_path.exists() else None
        if m:
            return client_addr(m.group(1))
        if not group.running():
            group.stop(2.0)
            last = " | ".join(tail(log_path, 5)) or "no output"
            raise BootError(f"atlas exited with code {group.popen.returncode} before it was ready: {last}")
        time.sleep(0.02)
    group.stop(5.0)
    raise BootError(f"atlas printed no 'atlas listening on' line within {ATLAS_READY_TIMEOUT_S:g}s")


# ---------------------------------------------------------------------- orchestration


class Orchestrator:
    """Starts the entries and drives each to its target state; an entry answering Deferred is retried.

    By default every entry starts at once: rbnx does not know the dependencies between packages (they
    resolve each other through the atlas), and a package whose input is not up yet answers Deferred and
    is retried with backoff, so starting in parallel is always safe and overlaps the slow part of each
    start (interpreter + imports, several seconds for MuJoCo/numba). ``parallel=False`` restores
    one-at-a-time starts (the next entry starts when the current one settled or is parked).
    """

    def __init__(self, entries: list[ResolvedEntry], env: dict[str, str], atlas_addr: str, opts: BootOptions,
                 stop: threading.Event, on_change: Any = None) -> None:
        self.atlas_addr = atlas_addr
        self.opts = opts
        self.stop = stop
        self.on_change = on_change or (lambda: None)
        self.runners = [EntryRunner(e, env, opts.log_dir / f"{e.name}.log", opts.timing) for e in entries]
        self.view = ProgressView([Row(e.name, e.kind) for e in entries], enabled=opts.progress)
        self._settle_order: list[EntryRunner] = []

    def _sync_view(self) -> None:
        for r in self.runners:
            before = self.view.row(r.name)
            if (before.state, before.detail) != (r.state, r.detail):
                self.view.set(r.name, r.state, r.detail)
                if r.settled and r not in self._settle_order:
                    self._settle_order.append(r)
                self.on_change()
        self.view.tick()

    def start_all(self) -> None:
        """Spawn every entry now, before the atlas is up (its address known in advance): the interpreter
        start and imports of each package overlap the atlas's start; packages retry registering while
        the atlas is not listening yet. A fresh atlas holds no stale records, so none is looked up."""
        for r in self.runners:
            r.start(self.atlas_addr, None)
        self.on_change()

    def boot(self, deadline: float) -> bool:
        """Run until every entry settled, the boot deadline passed, or a stop was requested."""
        queue = [r for r in self.runners if r.proc is None and not r.settled]
        current: EntryRunner | None = None
        with Atlas(self.atlas_addr, timeout=2.0) as atlas:
            while not self.stop.is_set():
                while (current is None or current.settled or current.parked or self.opts.parallel) and queue:
                    current = queue.pop(0)
                    current.start(self.atlas_addr, atlas)
                    self.on_change()
                now = time.monotonic()
                before = [r.state for r in self.runners]
                for r in self.runners:
                    r.step(atlas, now, deadline)
                if [r.state for r in self.runners] != before:
                    # progress (registered / inactive / active) may be what a parked entry waits for
                    for r in self.runners:
                        r.retry_now(now)
                self._sync_view()
                if not queue and all(r.settled for r in self.runners):
                    break
                if self.refused():  # final: waiting out the deadline cannot change a refused config
                    break
                self.stop.wait(0.05)
        for r in self.runners:
            if not r.settled:
                r.abort()
        self.view.finish()
        return all(r.ok for r in self.runners)

    def refused(self) -> list[EntryRunner]:
        """Entries whose CMD_INIT was refused (Err, not Deferred)."""
        return [r for r in self.runners if r.refused]

    def shutdown_order(self) -> list[EntryRunner]:
        """Reverse of the order entries became ready (dependents first); unsettled/failed ones first."""
        settled = [r for r in self._settle_order if r.ok]
        rest = [r for r in self.runners if r not in settled]
        return list(reversed(rest)) + list(reversed(settled))

    def shutdown(self, term_timeout: float) -> None:
        for r in self.shutdown_order():
            if r.proc is None:
                continue
            self.view.set(r.name, "stopping")
            outcome = r.shutdown(term_timeout)
            self.view.set(r.name, "stopped", outcome)
        self.view.finish()


# ---------------------------------------------------------------------- the command


class _Signals:
    """SIGINT/SIGTERM set an event instead of raising, so shutdown runs in order; a second signal hurries."""

    def __init__(self) -> None:
        self.stop = threading.Event()
        self.count = 0
        self._old: dict[int, Any] = {}

    def _handler(self, signum: int, _frame: FrameType | None) -> None:
        self.count += 1
        self.stop.set()

    def install(self) -> None:
        for s in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
            self._old[s] = signal.signal(s, self._handler)

    def restore(self) -> None:
        for s, h in self._old.items():
            signal.signal(s, h)


def _summary(orch: Orchestrator, name: str, atlas_addr: str, elapsed: float, log_dir: Path, verbose: bool) -> None:
    ready = [r for r in orch.runners if r.ok]
    print(f"boot: {len(ready)}/{len(orch.runners)} entries ready in {elapsed:.2f}s "
          f"(deploy {name!r}, atlas {atlas_addr}, logs {log_dir})", flush=True)
    for r in orch.runners:
        when = f"{r.ready_at - r.started_at:.2f}s" if r.ok else "-"
        print(f"  {r.name:<20} {r.entry.kind:<9} {r.state:<9} {when:>7}  pid {r.proc.pid if r.proc else '-'}")
    failed = [r for r in orch.runners if not r.ok]
    if failed:
        print("failures:")
        for r in failed:
            print(f"  {r.name} ({r.entry.kind}): {r.failure or r.state}  [log {r.log_path}]")
            for line in r.log_tail[-(15 if verbose else 6):]:
                print(f"    | {line}")
    sys.stdout.flush()


def run_boot(deploy: ResolvedDeploy, opts: BootOptions) -> int:
    """The whole boot; returns the exit code (0 all ready, 1 some failed, 2 a CMD_INIT refused its config
    (everything started is stopped), 130 interrupted during boot)."""
    sig = _Signals()
    sig.install()
    procs.set_supervised(not opts.exit_after_boot)
    opts.log_dir.mkdir(parents=True, exist_ok=True)
    spath = state_path(deploy.path, deploy.atlas_listen, pid=os.getpid())
    atlas_group: ProcGroup | None = None
    orch: Orchestrator | None = None
    gateway: Any = None
    state: dict[str, Any] = {"pid": os.getpid(), "deploy": str(deploy.path), "log_dir": str(opts.log_dir.resolve()),
                             "started": time.time(), "atlas": None, "atlas_proc": None, "children": []}
    state["start_ticks"] = proc_start_ticks(os.getpid())
    # The deployment token (system.atlas.auth: token, the default): atlas and children get it in their
    # environment, this process adopts it (gateway, Driver calls), the 0600 state file records it.
    token = deploytoken.new_token() if deploy.atlas_auth != "none" else ""
    deploytoken.adopt(token)
    base_env = deploytoken.boot_env(deploy.env, token, deploy.atlas_allowed_hosts)
    if token:
        state["token"] = token

    save_lock = threading.Lock()  # the gateway thread records its URL too

    def save() -> None:
        with save_lock:
            if orch is not None:
                state["children"] = [r.describe() for r in orch.runners if r.proc is not None]
            write_state(spath, state, copy_to=opts.log_dir / "rbnx-boot.json")

    def gateway_ready(url: str) -> None:
        with save_lock:
            state["gateway"] = url
        save()
        print(f"MCP gateway: {url}", flush=True)

    code = 1
    keep = False
    try:
        t0 = time.monotonic()
        save()
        listen = deploy.atlas_listen
        env = dict(base_env, RBNX_DEPLOY_NAME=deploy.name)  # runners key RBNX_RUN_DIR by it + the atlas
        try:
            atlas_group = spawn_atlas(listen, base_env, opts.log_dir / "atlas.log", deploy.atlas_log)
            if opts.parallel and _split(listen)[1] != 0:  # address known before the atlas is up
                orch = Orchestrator(deploy.entries, env, client_addr(listen), opts, sig.stop, on_change=save)
                orch.start_all()
            atlas_addr = wait_atlas(atlas_group, opts.log_dir / "atlas.log")
        except BootError as exc:
            print(f"rbnx boot: {exc}", file=sys.stderr)
            return 1
        state["atlas"] = atlas_addr
        state["atlas_proc"] = {"pid": atlas_group.pid, "pgid": atlas_group.pgid,
                               "start_ticks": atlas_group.start_ticks}
        save()
        if opts.verbose:
            print(f"atlas listening on {atlas_addr} (pid {atlas_group.pid})", flush=True)
        if orch is None:
            orch = Orchestrator(deploy.entries, env, atlas_addr, opts, sig.stop, on_change=save)
        gateway = _start_gateway(orch, atlas_addr, opts, sig, gateway_ready)
        all_ok = orch.boot(deadline=t0 + opts.boot_timeout)
        save()
        if sig.stop.is_set():
            print("rbnx boot: interrupted; shutting down", flush=True)
            code = 130
        elif orch.refused():
            _report_refused(orch)
            return 2
        else:
            _summary(orch, deploy.name, atlas_addr, time.monotonic() - t0, opts.log_dir, opts.verbose)
            code = 0 if all_ok else 1
            if opts.exit_after_boot:
                print(f"left running; stop with: rbnx shutdown -f {deploy.path}", flush=True)
                keep = True
                return code
            print(f"running; Ctrl-C or `rbnx shutdown -f {deploy.path}` to stop", flush=True)

            def respawn_atlas() -> ProcGroup:
                nonlocal atlas_group
                group = spawn_atlas(atlas_addr, base_env, opts.log_dir / "atlas.log", deploy.atlas_log,
                                    append=True)
                atlas_group = group
                wait_atlas(group, opts.log_dir / "atlas.log", after=group.log_offset)
                state["atlas_proc"] = {"pid": group.pid, "pgid": group.pgid, "start_ticks": group.start_ticks,
                                       "restarts": sup.atlas_tracker.restarts}
                save()
                return group

            with Atlas(atlas_addr, timeout=2.0) as atlas:
                sup = Supervisor(orch.runners, atlas, opts.boot_timeout, save, view=orch.view,
                                 atlas_proc=atlas_group, atlas_policy=deploy.atlas_restart,
                                 respawn_atlas=respawn_atlas)
                notes = NoteWatch()  # e.g. "nav2: warming up the planner (…): 20 s so far"
                while not sig.stop.wait(SUPERVISE_PERIOD_S):
                    sup.poll()
                    notes.poll(atlas, [r.name for r in orch.runners])
        return code
    finally:
        if not keep:
            _teardown(orch, atlas_group, opts, sig, gateway)
            remove_state(spath)
        sig.restore()


def _report_refused(orch: Orchestrator) -> None:
    """One line per entry whose CMD_INIT refused its config (entry and field), then what happens next."""
    for r in orch.refused():
        print(f"rbnx boot: {r.entry.key} ({r.name}): {r.failure} [log {r.log_path}]", file=sys.stderr, flush=True)
    print("rbnx boot: a refused CMD_INIT is final; stopping everything started", file=sys.stderr, flush=True)


def _start_gateway(orch: Orchestrator, atlas_addr: str, opts: BootOptions, sig: _Signals, on_ready: Any) -> Any:
    """The MCP gateway (agents' one endpoint; its `shutdown` tool stops this boot), started on a thread
    while the entries boot; None when off (and with --exit-after-boot: it lives in this process)."""
    if not opts.gateway or opts.exit_after_boot:
        return None
    from rbnx.gateway import BootGateway
    from robonix_api import telemetry

    telemetry.setup("rbnx")
    return BootGateway(atlas_addr, orch.runners, sig.stop.set, opts.timing.driver_timeout, on_ready).start()


def _teardown(orch: Orchestrator | None, atlas_group: ProcGroup | None, opts: BootOptions, sig: _Signals,
              gateway: Any = None) -> None:
    """Reverse-order shutdown of entries, then the gateway and the atlas."""
    if orch is None and atlas_group is None:
        return
    term = opts.term_timeout if sig.count < 2 else min(opts.term_timeout, 2.0)
    print("shutting down…", flush=True)
    if orch is not None:
        orch.shutdown(term)
    if gateway is not None:
        gateway.stop()
    if atlas_group is not None:
        atlas_group.stop(min(term, 10.0))
        print("atlas stopped", flush=True)
