"""`rbnx validate` (subprocess): accepts the example files, rejects broken copies with one line each."""

from __future__ import annotations

from pathlib import Path

from .rbnx_testutil import MINIMAL, copy_minimal, make_env, run


def test_examples_validate(tmp_path: Path) -> None:
    env = make_env(tmp_path)
    res = run(["validate", str(MINIMAL / "deploy.yaml"), str(MINIMAL / "odom_primitive"),
               str(MINIMAL / "odom_consumer" / "package_manifest.yaml")], env, tmp_path)
    assert res.returncode == 0, res.stdout + res.stderr
    assert res.stdout.count(": ok") == 3


def test_broken_copies_rejected(tmp_path: Path) -> None:
    root = copy_minimal(tmp_path)
    env = make_env(tmp_path)
    pm = root / "odom_consumer" / "package_manifest.yaml"
    pm.write_text(pm.read_text().replace("start:", "begin:").replace("  license: Apache-2.0\n", ""))
    res = run(["validate", str(root / "deploy.yaml")], env, tmp_path)
    assert res.returncode == 2
    assert res.stdout.splitlines() == [f"{pm}: package.license: missing required key",
                                       f"{pm}: start: missing required key"]
    assert "2 problems found" in res.stderr
    res = run(["validate", str(pm)], env, tmp_path)
    assert res.returncode == 2
    assert len(res.stdout.splitlines()) == 2

    d = root / "deploy.yaml"
    d.write_text(d.read_text().replace("name: odom_primitive", "name: odom_consumer"))
    res = run(["validate", str(d)], env, tmp_path)
    assert res.returncode == 2
    assert f"{d}: primitive[0].name: duplicate name 'odom_consumer' (first used by service[0])" in res.stdout
    (root / "junk.yaml").write_text("a: [1\n")
    res = run(["validate", str(root / "junk.yaml")], env, tmp_path)
    assert res.returncode == 2
    assert res.stdout.startswith(f"{root / 'junk.yaml'}:2:")


def test_build_runs_hooks_and_stamps(tmp_path: Path) -> None:
    root = copy_minimal(tmp_path)
    env = make_env(tmp_path)
    res = run(["build", "-f", str(root / "deploy.yaml")], env, tmp_path)
    assert res.returncode == 0, res.stdout + res.stderr
    assert (root / "odom_primitive" / ".rbnx-built").exists()
    assert (root / "odom_consumer" / ".rbnx-built").exists()
    pm = root / "odom_primitive" / "package_manifest.yaml"
    pm.write_text(pm.read_text().replace('build: "true"', 'build: test "$RBNX_BUILD_CLEAN" = 1 && exit 4'))
    res = run(["build", "-p", str(root / "odom_primitive"), "--clean"], env, tmp_path)
    assert res.returncode == 1
    assert "FAILED" in res.stdout
    assert "exit code 4" in res.stdout
