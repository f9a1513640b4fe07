"""``rbnx boot`` of a deploy file through the console script (a real atlas, real children) for the boot
tests: wait for its summary, read the state file's PIDs, SIGINT it and check every recorded process exits."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from pathlib import Path
from types import TracebackType
from typing import Any

from .procs import alive, wait_until


def rbnx_cmd() -> list[str]:
    exe = Path(sys.executable).parent / "rbnx"
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "rbnx.cli"]


class RbnxBoot:
    """``rbnx boot -f deploy [extra…]`` in ``tmp`` (own state dir, atlas on a port of the OS's choosing, logs
    in tmp/logs, output in tmp/boot.out); killed on leaving the ``with`` block if still running."""

    def __init__(self, deploy: Path, tmp: Path, *extra: str) -> None:
        self.out, self.logs, self.state_dir = tmp / "boot.out", tmp / "logs", tmp / "state"
        env = dict(os.environ, RBNX_STATE_DIR=str(self.state_dir), RBNX_ATLAS_LISTEN="127.0.0.1:0",
                   RBNX_PYTHON=sys.executable, PYTHONUNBUFFERED="1")
        for name in ("ROBONIX_ATLAS", "RBNX_INSTANCE_NAME", "RBNX_DEPLOY_MANAGED"):
            env.pop(name, None)
        with open(self.out, "w") as fh:
            self.proc = subprocess.Popen(rbnx_cmd() + ["boot", "-f", str(deploy), "--log-dir", str(self.logs), *extra],
                                         env=env, cwd=tmp, stdout=fh, stderr=subprocess.STDOUT)
        self.pids: list[int] = []
        self._token_before: str | None = os.environ.get("ROBONIX_DEPLOY_TOKEN")

    def __enter__(self) -> RbnxBoot:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(30)
        if self._token_before is None:  # the boot's token was this test's only while the boot ran
            os.environ.pop("ROBONIX_DEPLOY_TOKEN", None)
        else:
            os.environ["ROBONIX_DEPLOY_TOKEN"] = self._token_before

    @property
    def token(self) -> str:
        return str(self.state().get("token") or "")

    def adopt_token(self) -> None:
        """The test process acts as a client of this deployment: the SDK's clients send its token."""
        token = self.token
        if token:
            os.environ["ROBONIX_DEPLOY_TOKEN"] = token

    def output(self) -> str:
        return self.out.read_text()

    def log(self, entry: str) -> str:
        return (self.logs / f"{entry}.log").read_text()

    def wait_ready(self, entries: int, timeout_s: float = 180) -> None:
        """Until the summary says all ``entries`` are ready; fails at once if rbnx boot exits."""
        def ready() -> bool:
            text = self.output()
            if self.proc.poll() is not None:
                raise AssertionError(f"rbnx boot exited {self.proc.returncode}:\n{text}")
            return f"{entries}/{entries} entries ready" in text

        wait_until(ready, timeout_s, "boot summary", 0.2)
        self.adopt_token()

    def state(self) -> dict[str, Any]:
        """The (single) boot state file; records the PIDs of rbnx, the atlas and every child."""
        (state_file,) = self.state_dir.glob("boot-*.json")
        st = json.loads(state_file.read_text())
        self.pids = [st["pid"], st["atlas_proc"]["pid"], *(c["pid"] for c in st["children"])]
        return st

    def interrupt(self, timeout_s: float = 180) -> None:
        """SIGINT (Ctrl-C) by PID; rbnx boot must exit 0."""
        self.proc.send_signal(signal.SIGINT)
        assert self.proc.wait(timeout_s) == 0, self.output()

    def wait_all_exited(self, timeout_s: float = 30) -> None:
        wait_until(lambda: not any(alive(p) for p in self.pids), timeout_s, "every recorded process to exit")
