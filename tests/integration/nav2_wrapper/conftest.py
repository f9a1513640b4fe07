"""Real processes for the navigation provider tests: an in-process atlas plus provider children.

Each child (nav provider, HAL, the stand-in map provider) is found through the atlas like any consumer
would, driven over its lifecycle Driver, and stopped by its own PID (SIGTERM, SIGKILL after a grace
period); the fixtures assert none is left behind. Deadlines are generous (shared 2-core machine).
The helpers live in tests/support.
"""

from __future__ import annotations

from support.fixtures import atlas, procs_fixture
from support.procs import ACTIVATE, DEACTIVATE, HAL, INIT, MAP_PROVIDER, NAV, SHUTDOWN, Proc, wait_until

__all__ = ["ACTIVATE", "DEACTIVATE", "HAL", "INIT", "MAP_PROVIDER", "NAV", "SHUTDOWN", "Proc", "atlas",
           "wait_until"]

procs = procs_fixture(Proc, newest_first=False)
