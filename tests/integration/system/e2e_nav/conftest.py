"""Real processes for the navigation acceptance tests: an in-process atlas plus HAL, SLAM and nav children.

Every child is found through the atlas like any consumer would find it, driven over its lifecycle Driver
and stopped by its own PID (SIGTERM, SIGKILL after a grace period); the fixtures assert none is left.
The children are launched together and only then awaited (``Proc.ready()``), so their (heavy) imports
overlap. Deadlines are generous: the machine is shared and has two cores. The helpers live in tests/support.
"""

from __future__ import annotations

from support.fixtures import atlas, procs_fixture
from support.procs import ACTIVATE, DEACTIVATE, HAL, INIT, NAV, SLAM, Proc
from support.wait import wait_until

__all__ = ["ACTIVATE", "DEACTIVATE", "HAL", "INIT", "NAV", "SLAM", "Proc", "atlas", "wait_until"]


class E2eProc(Proc):
    """A provider child that is only launched by ``procs(cmd, name, **env)``: call ``ready()`` before using
    it. ``init()`` retries while CMD_INIT answers Deferred, as ``rbnx boot`` does."""

    consumer_id = "e2e_nav_test"
    wait_ready = False
    init_retry_s = 90.0


# stopped by PID newest first at module end; none may be left and every exit must be clean (code 0)
procs = procs_fixture(E2eProc, clean_exit=True)
