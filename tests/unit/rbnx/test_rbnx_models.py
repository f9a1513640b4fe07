"""Deploy/package models: every problem reported once with its key path; env expansion; order."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from rbnx.models import (
    ManifestProblems,
    PackageManifest,
    detect_kind,
    load_deploy,
    load_package,
    loc_to_path,
    manifest_file,
)

PKG = {
    "manifestVersion": 1,
    "package": {"name": "p", "version": 1.0, "description": "d", "license": "MIT"},
    "start": "python x.py",
}


def write_pkg(root: Path, name: str, extra: dict | None = None, fname: str = "package_manifest.yaml") -> Path:
    d = root / name
    d.mkdir(parents=True, exist_ok=True)
    data = {**PKG, "package": {**PKG["package"], "name": name}, **(extra or {})}
    (d / fname).write_text(yaml.safe_dump(data))
    return d


def write_deploy(tmp: Path, data: dict | str) -> Path:
    p = tmp / "deploy.yaml"
    p.write_text(data if isinstance(data, str) else yaml.safe_dump(data, sort_keys=False))
    return p


def problems(path: Path, env: dict[str, str] | None = None) -> list[str]:
    with pytest.raises(ManifestProblems) as ei:
        load_deploy(path, base_env=env or {})
    return ei.value.lines


def test_valid_deploy_resolves_packages_and_config(tmp_path: Path) -> None:
    write_pkg(tmp_path, "a")
    write_pkg(tmp_path, "b")
    d = write_deploy(tmp_path, {"manifestVersion": 1, "name": "x",
                                "primitive": [{"name": "a", "path": "a", "config": {"k": 1}}],
                                "skill": [{"name": "b", "path": "b"}]})
    dep = load_deploy(d, base_env={})
    assert [(e.name, e.kind) for e in dep.entries] == [("a", "primitive"), ("b", "skill")]
    assert dep.entries[0].config == {"k": 1}
    assert dep.atlas_listen == "127.0.0.1:50051"
    assert dep.entries[0].manifest.package.version == "1.0"


def test_every_problem_named_by_key_path(tmp_path: Path) -> None:
    write_pkg(tmp_path, "nav2")
    d = write_deploy(tmp_path, {
        "manifestVersion": 1, "name": "x",
        "service": [{"name": "nav2", "path": "nav2"}, {"name": "nav2", "path": "nav2"},
                    {"name": "c", "path": "missing"}, {"name": "d", "path": "nav2", "manifest": "jetson"}],
    })
    lines = problems(d)
    assert f"{d}: service[1].name: duplicate name 'nav2' (first used by service[0])" in lines
    assert any(line.startswith(f"{d}: service[2].path: no such directory 'missing'") for line in lines)
    assert any(line.startswith(f"{d}: service[3].manifest: package manifest not found")
               and line.endswith("package_manifest.jetson.yaml") for line in lines)
    assert len(lines) == 3


def test_schema_errors_one_line_each(tmp_path: Path) -> None:
    d = write_deploy(tmp_path, {"manifestVersion": 0, "name": "", "system": {"atlas": {"listen": "nope"}},
                                "service": [{"name": "", "path": "a"}, {"name": "b", "path": "a", "url": "u"},
                                            {"name": "c"}, "str"]})
    lines = problems(d)
    assert lines == [
        f"{d}: manifestVersion: must be >= 1",
        f"{d}: name: string should have at least 1 character",
        f"{d}: system.atlas.listen: expected HOST:PORT, got 'nope'",
        f"{d}: service[0].name: must not be empty",
        f"{d}: service[1]: exactly one of 'path' or 'url' must be set",
        f"{d}: service[2]: exactly one of 'path' or 'url' must be set",
        f"{d}: service[3]: input should be a valid dictionary or instance of DeployEntry",
    ]


def test_yaml_syntax_error_has_file_and_line(tmp_path: Path) -> None:
    d = write_deploy(tmp_path, "manifestVersion: 1\nname: x\nservice:\n  - name: a\n   path: [b\n")
    lines = problems(d)
    assert len(lines) == 1
    assert lines[0].startswith(f"{d}:5:")
    assert "YAML syntax error" in lines[0]


def test_empty_and_non_mapping(tmp_path: Path) -> None:
    assert problems(write_deploy(tmp_path, "")) == [f"{tmp_path / 'deploy.yaml'}: empty file"]
    assert "top level must be a mapping" in problems(write_deploy(tmp_path, "- a\n"))[0]


def test_env_applied_then_expanded(tmp_path: Path) -> None:
    write_pkg(tmp_path, "a")
    d = write_deploy(tmp_path, {"manifestVersion": 1, "name": "x",
                                "env": {"PKGS": "${HOME_DIR}", "PORT": 7000},
                                "system": {"atlas": {"listen": "127.0.0.1:$PORT"}},
                                "primitive": [{"name": "a", "path": "$PKGS/a",
                                               "config": {"m": "${MAPS:-/tmp/maps}", "lit": "$$x"}}]})
    dep = load_deploy(d, base_env={"HOME_DIR": str(tmp_path)})
    assert dep.atlas_listen == "127.0.0.1:7000"
    assert dep.env["PKGS"] == str(tmp_path)
    assert dep.env["PORT"] == "7000"
    assert dep.entries[0].root == (tmp_path / "a").resolve()
    assert dep.entries[0].config == {"m": "/tmp/maps", "lit": "$x"}


def test_undefined_variable_is_a_problem(tmp_path: Path) -> None:
    d = write_deploy(tmp_path, {"manifestVersion": 1, "name": "x",
                                "primitive": [{"name": "a", "path": "${NOPE}/a"}]})
    assert problems(d) == [f"{d}: primitive[0].path: undefined variable $NOPE"]


def test_url_needs_local_checkout(tmp_path: Path) -> None:
    d = write_deploy(tmp_path, {"manifestVersion": 1, "name": "x",
                                "service": [{"name": "m", "url": "https://github.com/o/service-map-rbnx.git"}]})
    lines = problems(d)
    assert len(lines) == 1
    assert "service[0].url: cannot fetch" in lines[0]
    assert "service-map-rbnx" in lines[0]
    write_pkg(tmp_path / "rbnx-packages", "service-map-rbnx")
    assert load_deploy(d, base_env={}).entries[0].root.name == "service-map-rbnx"


def test_manifest_target_picks_variant(tmp_path: Path) -> None:
    root = write_pkg(tmp_path, "a")
    write_pkg(tmp_path, "a", {"start": "jetson start"}, fname="package_manifest.jetson-native.yaml")
    assert manifest_file(root, "jetson-native").name == "package_manifest.jetson-native.yaml"
    assert manifest_file(root, None).name == "package_manifest.yaml"
    d = write_deploy(tmp_path, {"manifestVersion": 1, "name": "x",
                                "primitive": [{"name": "a", "path": "a", "manifest": "jetson-native"}]})
    assert load_deploy(d, base_env={}).entries[0].manifest.start == "jetson start"


def test_sections_boot_in_file_order(tmp_path: Path) -> None:
    write_pkg(tmp_path, "a")
    d = write_deploy(tmp_path, "manifestVersion: 1\nname: x\nservice:\n  - {name: b, path: a}\n"
                               "primitive:\n  - {name: a, path: a}\n")
    assert [e.name for e in load_deploy(d, base_env={}).entries] == ["b", "a"]


def test_unknown_deploy_keys_are_errors(tmp_path: Path) -> None:
    """A misspelt key silently ignored boots a different system than the file describes."""
    write_pkg(tmp_path, "a")
    d = write_deploy(tmp_path, {"manifestVersion": 1, "name": "x", "extra": 1,
                                "primitive": [{"name": "a", "path": "a", "confg": {}}]})
    with pytest.raises(ManifestProblems) as exc:
        load_deploy(d, base_env={})
    assert exc.value.lines == [
        f"{d}: extra: unknown key (expected one of: manifestVersion, name, env, system, primitive, service, skill)",
        f"{d}: primitive[0].confg: unknown key (did you mean 'config'?)"]


def test_package_manifest_rules(tmp_path: Path) -> None:
    pm = PackageManifest.model_validate({**PKG, "future_key": {"x": 1}, "capabilities": None})
    assert pm.capabilities == []
    assert pm.stop is None
    root = write_pkg(tmp_path, "bad", {"start": " ", "manifestVersion": 0, "package": {"name": "bad"}})
    with pytest.raises(ManifestProblems) as ei:
        load_package(root)
    f = root / "package_manifest.yaml"
    assert ei.value.lines == [
        f"{f}: manifestVersion: must be >= 1",
        f"{f}: package.version: missing required key",
        f"{f}: package.description: missing required key",
        f"{f}: package.license: missing required key",
        f"{f}: start: must not be empty",
    ]


def test_detect_kind_and_loc() -> None:
    assert detect_kind(PKG) == "package"
    assert detect_kind({"service": []}) == "deploy"
    assert detect_kind({"x": 1}) == "unknown"
    assert loc_to_path(("service", 1, "name")) == "service[1].name"
    assert loc_to_path(()) == "(top level)"
