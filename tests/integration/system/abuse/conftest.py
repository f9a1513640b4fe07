"""The abuse suite's shared deployment (booted once for the whole directory) and its report: how many
hostile inputs each test tried, printed at the end of the run."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from .deployment import Deployment, boot_deployment, git_status, tree_digest

TRIED: dict[str, int] = {}


@pytest.fixture(scope="package")
def deployment(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Deployment]:
    tmp = tmp_path_factory.mktemp("abuse")
    repo_before = git_status()
    dep = boot_deployment(tmp)
    skip = {dep.maps_root, tmp / "logs", tmp / "state", tmp / "boot.out"}
    outside_before = tree_digest(tmp, skip)
    try:
        yield dep
        dep.assert_alive()
        assert tree_digest(tmp, skip) == outside_before, "a file outside the maps root changed"
        assert git_status() == repo_before, "the repository's files changed"
    finally:
        for what, n in dep.tried.items():
            TRIED[what] = TRIED.get(what, 0) + n
        with dep.boot:
            dep.boot.interrupt()
            dep.boot.wait_all_exited()


def pytest_terminal_summary(terminalreporter: pytest.TerminalReporter) -> None:
    if TRIED:
        total = sum(TRIED.values())
        terminalreporter.write_sep("-", f"abuse suite: {total} hostile inputs tried")
        for what, n in sorted(TRIED.items()):
            terminalreporter.write_line(f"  {n:6d}  {what}")
