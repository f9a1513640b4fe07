"""Fixtures for the DDS tests: a node per test and the helper publisher process."""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from robonix_api.dds import DdsNode

from .dds_helpers import stop_process

PEER = Path(__file__).with_name("dds_peer.py")


@pytest.fixture
def node() -> Iterator[DdsNode]:
    n = DdsNode(name="test")
    yield n
    n.close()


@pytest.fixture(scope="module")
def peer() -> Iterator[subprocess.Popen]:
    proc = subprocess.Popen([sys.executable, str(PEER)], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        line = proc.stdout.readline()  # blocks until READY or the child dies (EOF)
        if line.strip() != "READY":
            stop_process(proc)
            pytest.fail(f"peer did not start: {line!r} {proc.stderr.read()[-2000:]}")
        yield proc
    finally:
        stop_process(proc)
