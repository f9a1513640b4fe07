"""Real provider processes for the trust tests: an in-process atlas per module and ``procs`` children
stopped by PID at module end (see tests/support/fixtures.py)."""

from support.fixtures import atlas, procs_fixture

procs = procs_fixture()

__all__ = ["atlas", "procs"]
