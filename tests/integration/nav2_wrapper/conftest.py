"""Real processes for the navigation provider tests: an in-process atlas plus provider children.

Each child (nav provider, HAL, the stand-in map provider) is found through the atlas like any consumer
would, driven over its lifecycle Driver, and stopped by its own PID (SIGTERM, SIGKILL after a grace
period); the fixtures assert none is left behind. Deadlines are generous (shared 2-core machine).
The helpers live in tests/support.
"""

from __future__ import annotations

from collections.abc import Callable

from support.fixtures import atlas, procs_fixture
from support.procs import ACTIVATE, DEACTIVATE, HAL, INIT, MAP_PROVIDER, NAV, SHUTDOWN, Proc, wait_until

__all__ = ["ACTIVATE", "DEACTIVATE", "HAL", "INIT", "MAP_PROVIDER", "NAV", "SHUTDOWN", "Proc", "atlas",
           "start_sim_nav", "wait_until"]

procs = procs_fixture(Proc, newest_first=False)

SIM_HAL_CFG = {"scene": "apartment", "real_time_factor": 4.0, "use_sim_time": True}
SIM_NAV_CFG = {"params_profile": "sim", "use_sim_time": True, "action_wait_s": 90, "clock_timeout_s": 5.0}


def start_sim_nav(procs: Callable[[str, str], Proc], tag: str) -> tuple[Proc, Proc]:
    """The HAL in the apartment (rtf 4), the stand-in map provider and navigation, all initialised and the
    HAL and navigation ACTIVE; returns (hal, nav). ``tag`` suffixes the provider ids."""
    hal = procs(HAL, f"panda_{tag}")
    mapper = procs(MAP_PROVIDER, f"map_{tag}")
    nav = procs(NAV, f"nav_{tag}")
    assert hal.driver(INIT, SIM_HAL_CFG)[0], hal.log()[-3000:]
    assert hal.driver(ACTIVATE)[0]
    assert mapper.driver(INIT, {"scene": "apartment"})[0], mapper.log()[-3000:]
    ok, state, err = nav.driver(INIT, SIM_NAV_CFG)
    assert ok, (err, nav.log()[-4000:])
    assert state == "inactive", (err, nav.log()[-4000:])
    assert nav.driver(ACTIVATE)[:2] == (True, "active")
    return hal, nav
