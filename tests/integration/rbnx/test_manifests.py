"""Every manifest and deploy file in the repository validates under `rbnx validate`; broken copies are rejected
clearly (which manifests exist and how the nav targets differ: tests/unit/rbnx/test_manifest_set.py)."""

from __future__ import annotations

import subprocess
import sys

import pytest
import yaml
from support.repo import REPO, repo_files

MANIFESTS = repo_files("package_manifest*.yaml")
DEPLOYS = repo_files("deploy*.yaml")


def rbnx(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "rbnx.cli", *args], capture_output=True, text=True, timeout=60)


@pytest.mark.parametrize("path", MANIFESTS + DEPLOYS, ids=lambda p: p.relative_to(REPO).as_posix())
def test_validate_accepts_repo_file(path):
    r = rbnx("validate", str(path))
    assert r.returncode == 0, r.stdout + r.stderr


def test_validate_rejects_broken_copies_one_line_per_problem(tmp_path):
    doc = yaml.safe_load((REPO / "package_manifest.yaml").read_text())
    del doc["start"]
    doc["manifestVersion"] = 0
    bad = tmp_path / "package_manifest.yaml"
    bad.write_text(yaml.safe_dump(doc))
    r = rbnx("validate", str(bad))
    assert r.returncode == 2
    lines = [ln for ln in (r.stdout + r.stderr).splitlines() if ln.strip()]
    assert any("start" in ln for ln in lines)
    assert any("manifestVersion" in ln for ln in lines)
    assert "Traceback" not in r.stdout + r.stderr
    bad.write_text("package: [unclosed\n")
    r = rbnx("validate", str(bad))
    assert r.returncode == 2
    assert "Traceback" not in r.stdout + r.stderr
