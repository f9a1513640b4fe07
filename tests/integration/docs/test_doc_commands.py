"""Runs the shell blocks of README.md and docs/ marked ``<!-- doc-test: run -->`` (or ``run with-atlas``)
exactly as written, from the repository root, with this environment's ``rbnx`` on PATH and a throw-away
HOME, and expects exit code 0. The other blocks name the test that covers them; tests/unit/test_docs_site.py
checks that every block is marked and that the named tests exist (tests/support/doc_blocks.py)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from support.doc_blocks import REPO, Block, all_blocks, run_mode
from support.fixtures import atlas  # noqa: F401  (fixture)

RUN_TIMEOUT_S = 240.0


def _runnable() -> list[Block]:
    """Each distinct runnable block once (docs/index.md repeats the README's)."""
    seen: set[tuple[str, str]] = set()
    out = []
    for b in all_blocks():
        mode = run_mode(b)
        if mode and (b.text, mode) not in seen:
            seen.add((b.text, mode))
            out.append(b)
    return out


BLOCKS = _runnable()


def test_there_are_blocks_to_run() -> None:
    assert len(BLOCKS) >= 2
    assert any(run_mode(b) == "with-atlas" for b in BLOCKS)


@pytest.mark.parametrize("block", BLOCKS, ids=[b.where for b in BLOCKS])
def test_doc_block_runs(block: Block, tmp_path: Path, request: pytest.FixtureRequest) -> None:
    env = {**os.environ, "HOME": str(tmp_path / "home"), "XDG_CACHE_HOME": str(tmp_path / "cache"),
           "XDG_DATA_HOME": str(tmp_path / "data"), "XDG_STATE_HOME": str(tmp_path / "state"),
           "TMPDIR": str(tmp_path), "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"}
    # keep the numba cache of this machine: a fresh one would only cost compile time
    env.setdefault("NUMBA_CACHE_DIR", str(Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
                                          / "robonix-nav" / "numba"))
    if run_mode(block) == "with-atlas":
        env["ROBONIX_ATLAS"] = request.getfixturevalue("atlas")
    (tmp_path / "home").mkdir()
    proc = subprocess.run(["bash", "-e", "-o", "pipefail", "-c", block.text], cwd=REPO, env=env,
                          capture_output=True, text=True, timeout=RUN_TIMEOUT_S, check=False)
    assert proc.returncode == 0, (f"{block.where} exited {proc.returncode}\n--- block\n{block.text}\n"
                                  f"--- stdout\n{proc.stdout[-3000:]}\n--- stderr\n{proc.stderr[-3000:]}")
    assert (proc.stdout + proc.stderr).strip(), f"{block.where} printed nothing"
