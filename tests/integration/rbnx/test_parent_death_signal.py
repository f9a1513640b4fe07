"""A child started through ``with_parent_death_signal`` gets the chosen signal when its parent dies.

``rbnx boot`` wraps providers with SIGTERM and ``rbnx demo`` wraps its boot with SIGINT (so the boot
still shuts the deployment down when the demo is SIGKILLed). Both ways of setting the signal are
checked: util-linux ``setpriv`` and the Python exec shim used where setpriv is missing.
"""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from support.procs import wait_until

# The child records the signal it got into a file (atomically) and exits; the parent starts it and then waits
# forever.
CHILD = r"""
import signal, sys, time
from pathlib import Path
out = Path(sys.argv[1])
def got(sig, _frame):
    part = out.with_suffix(".part")     # written whole, then renamed: the test reads it as soon as it exists
    part.write_text(signal.Signals(sig).name)
    part.replace(out)
    sys.exit(0)
signal.signal(signal.SIGINT, got)
signal.signal(signal.SIGTERM, got)
out.with_suffix(".ready").write_text("ready")
time.sleep(120)
"""

PARENT = r"""
import signal, subprocess, sys, time
import rbnx.boot.procs as procs
if sys.argv[1] == "shim":
    procs._SETPRIV = None
cmd = procs.with_parent_death_signal([sys.executable, "-c", sys.argv[3], sys.argv[4]], signal.Signals[sys.argv[2]])
child = subprocess.Popen(cmd, start_new_session=True)
print(child.pid, flush=True)
time.sleep(120)
"""


@pytest.mark.parametrize("how", ["setpriv", "shim"])
@pytest.mark.parametrize("sig", ["SIGINT", "SIGTERM"])
def test_child_gets_the_signal_when_its_parent_is_killed(tmp_path: Path, how: str, sig: str) -> None:
    import rbnx.boot.procs as procs

    if how == "setpriv" and procs._SETPRIV is None:
        pytest.skip("util-linux setpriv is not installed")
    out = tmp_path / "signal.txt"
    parent = subprocess.Popen([sys.executable, "-c", PARENT, how, sig, CHILD, str(out)],
                              stdout=subprocess.PIPE, text=True)
    assert parent.stdout is not None
    child_pid = int(parent.stdout.readline())
    try:
        wait_until(lambda: out.with_suffix(".ready").exists(), 60, "the child to start")
        parent.kill()
        parent.wait(timeout=30)
        wait_until(out.exists, 30, f"the child to receive {sig}")
        assert out.read_text() == sig
    finally:
        parent.kill()
        parent.wait(timeout=30)
        with contextlib.suppress(ProcessLookupError):
            os.kill(child_pid, signal.SIGKILL)
