"""The repository ships the expected package manifests, and the nav targets differ only in build/start/stop."""

from __future__ import annotations

import yaml
from support.repo import REPO, repo_files

MANIFESTS = repo_files("package_manifest*.yaml")


def test_repo_has_the_expected_manifests():
    names = {p.relative_to(REPO).as_posix() for p in MANIFESTS}
    assert {"package_manifest.yaml", "package_manifest.jetson-docker.yaml",
            "package_manifest.jetson-native.yaml", "hal_panda_mobile/package_manifest.yaml"} <= names


def test_nav_target_manifests_differ_only_in_build_start_stop():
    docs = [yaml.safe_load((REPO / n).read_text()) for n in
            ("package_manifest.yaml", "package_manifest.jetson-docker.yaml", "package_manifest.jetson-native.yaml")]
    strip = [{k: v for k, v in d.items() if k not in ("build", "start", "stop")} for d in docs]
    assert strip[0] == strip[1] == strip[2]
