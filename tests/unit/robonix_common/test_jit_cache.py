"""The numba cache directory chooser (the process-wide effect is tested as user nobody in the integration
test tests/integration/system/test_readonly_install.py)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from robonix_common.jit_cache import _seed, candidates, writable_dir


def test_candidates_prefer_xdg_then_home_then_tmp(tmp_path: Path) -> None:
    got = candidates({"XDG_CACHE_HOME": str(tmp_path / "x"), "HOME": str(tmp_path / "h")})
    assert got[:2] == [tmp_path / "x" / "robonix" / "numba", tmp_path / "h" / ".cache" / "robonix" / "numba"]
    assert got[2].name == "numba"
    assert got[2].parent.name.startswith("robonix-")


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only folders")
def test_read_only_and_missing_parents_are_not_writable(tmp_path: Path) -> None:
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    assert not writable_dir(ro / "cache")
    assert writable_dir(tmp_path / "a" / "b")


def test_unwritable_path_under_a_file(tmp_path: Path) -> None:
    (tmp_path / "file").write_text("x")
    assert not writable_dir(tmp_path / "file" / "cache")  # works as root too


def test_seed_copies_a_shipped_cache_and_keeps_existing_files(tmp_path: Path) -> None:
    src, dst = tmp_path / "shipped", tmp_path / "mine"
    (src / "sub").mkdir(parents=True)
    (src / "sub" / "k.nbi").write_text("shipped index")
    (src / "sub" / "k.nbc").write_text("shipped code")
    (dst / "sub").mkdir(parents=True)
    (dst / "sub" / "k.nbi").write_text("newer index")
    assert _seed(src, dst)
    assert (dst / "sub" / "k.nbi").read_text() == "newer index"
    assert (dst / "sub" / "k.nbc").read_text() == "shipped code"
