"""Suite-wide isolation: loopback-only DDS on a domain id of this run's own, short atlas timeouts.

Every process a test starts inherits this environment, so parallel runs on one machine never share
DDS traffic, and nothing leaves 127.0.0.1. Also makes tests/support (shared helpers) importable as
``support`` and the two test trees as the packages ``unit`` and ``integration``: pytest's default
(prepend) import mode already puts tests/ on sys.path, this keeps it so under other import modes.

Layout: tests/unit/<package> never starts a process, opens a socket or creates a DDS participant;
tests/integration/<package> (and integration/system for whole deployments) does. Every test under
tests/integration is marked ``integration`` here, by path, so ``-m "not integration"`` and
``-m integration`` select either half; every test under tests/integration/system/abuse is marked ``fuzz``.

Suites (pyproject addopts): the plain ``python -m pytest -q`` deselects ``slow`` and ``container`` tests and
runs the ``fuzz`` tests at a reduced count; .ci/run then runs ``ROBONIX_FUZZ=full python -m pytest -q -m
"slow or container or fuzz"``.
"""

import os
import sys
from pathlib import Path

import pytest

from rbnx.boot.entry import numba_cache_dir

REPO = Path(__file__).resolve().parent.parent
INTEGRATION = REPO / "tests" / "integration"
FUZZ = INTEGRATION / "system" / "abuse"
if str(REPO / "tests") not in sys.path:
    sys.path.insert(0, str(REPO / "tests"))

# A domain id per test run (0..232 is Cyclone's valid range with the default port mapping).
os.environ.setdefault("ROS_DOMAIN_ID", str(10 + os.getpid() % 200))
os.environ.setdefault("CYCLONEDDS_URI", (REPO / "config" / "cyclonedds_loopback.xml").as_uri())
# One numba cache for this process and every child, the one `rbnx boot` gives its children: without it the
# test process and the providers a test starts itself compile into __pycache__ while booted ones compile
# into the user cache, so a cold run paid the planner kernels' compile twice.
os.environ.setdefault("NUMBA_CACHE_DIR", str(numba_cache_dir(dict(os.environ))))


@pytest.fixture(scope="session", autouse=True)
def _maps_root(tmp_path_factory: pytest.TempPathFactory) -> None:
    """Saved maps may only live under the maps root: make it this run's temp base, so every test's
    ``tmp_path`` map_dir is allowed and nothing is written to the user's own maps."""
    if not os.environ.get("ROBONIX_MAPS_ROOT"):
        os.environ["ROBONIX_MAPS_ROOT"] = str(tmp_path_factory.getbasetemp().resolve())


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Mark every test under tests/integration ``integration`` and under its abuse suite ``fuzz`` (by path,
    so no file can forget it)."""
    for item in items:
        if item.path.is_relative_to(INTEGRATION):
            item.add_marker(pytest.mark.integration)
        if item.path.is_relative_to(FUZZ):
            item.add_marker(pytest.mark.fuzz)
