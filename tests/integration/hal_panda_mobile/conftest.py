"""Real processes for the provider tests: an in-process atlas, ``python -m hal_panda_mobile`` as a child.

Every child is stopped by its own PID (SIGTERM, then SIGKILL after a grace period) and the tests assert
it is gone; deadlines are generous because the machine is shared. The helpers live in tests/support.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator

import pytest
from support.fixtures import atlas, procs_fixture
from support.procs import HAL, Proc, wait_until

__all__ = ["HalProcess", "atlas", "wait_until"]


class HalProcess(Proc):
    """One ``python -m hal_panda_mobile`` child registered under ``name`` (start it with ``hal_factory``)."""

    consumer_id = "hal_test"
    ready_timeout_s = 90.0
    driver_timeout_s = 120.0


procs = procs_fixture(HalProcess, newest_first=False)


@pytest.fixture(scope="module")
def hal_factory(procs: Callable[..., HalProcess]) -> Iterator[Callable[[str], HalProcess]]:
    """``hal_factory(name)`` starts a HAL child; all are stopped (by PID) at module end."""
    return lambda name: procs(HAL, name)
