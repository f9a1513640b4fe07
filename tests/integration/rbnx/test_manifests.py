"""Every manifest and deploy file in the repository validates; broken copies are rejected clearly."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
import yaml

REPO = Path(__file__).resolve().parents[3]
SKIP_DIRS = {".git", ".venv", "venv", "node_modules", "rbnx-logs"}


def repo_files(pattern: str) -> list[Path]:
    return sorted(p for p in REPO.rglob(pattern) if not SKIP_DIRS.intersection(p.relative_to(REPO).parts))


MANIFESTS = repo_files("package_manifest*.yaml")
DEPLOYS = repo_files("deploy*.yaml")


def rbnx(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "rbnx.cli", *args], capture_output=True, text=True, timeout=60)


def test_repo_has_the_expected_manifests():
    names = {p.relative_to(REPO).as_posix() for p in MANIFESTS}
    assert {"package_manifest.yaml", "package_manifest.jetson-docker.yaml",
            "package_manifest.jetson-native.yaml", "hal_panda_mobile/package_manifest.yaml"} <= names


@pytest.mark.parametrize("path", MANIFESTS + DEPLOYS, ids=lambda p: p.relative_to(REPO).as_posix())
def test_validate_accepts_repo_file(path):
    r = rbnx("validate", str(path))
    assert r.returncode == 0, r.stdout + r.stderr


def test_nav_target_manifests_differ_only_in_build_start_stop():
    docs = [yaml.safe_load((REPO / n).read_text()) for n in
            ("package_manifest.yaml", "package_manifest.jetson-docker.yaml", "package_manifest.jetson-native.yaml")]
    strip = [{k: v for k, v in d.items() if k not in ("build", "start", "stop")} for d in docs]
    assert strip[0] == strip[1] == strip[2]


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
