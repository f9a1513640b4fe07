"""`rbnx validate` / `rbnx boot` check each entry's config against its package's own schema (``configSchema``
in the package manifest, the function CMD_INIT calls) and refuse unknown keys of the deploy file."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

import hal_panda_mobile.config  # noqa: F401  (mujoco's import runs a helper process: at collection, not in a test)
from rbnx.cli import main
from rbnx.models import ManifestProblems, load_deploy

REPO = Path(__file__).resolve().parents[3]
SIM = REPO / "examples" / "sim" / "deploy.yaml"


def sim_copy(tmp_path: Path, edit: object = None) -> Path:
    """examples/sim/deploy.yaml with absolute package paths (so it can live in tmp_path), edited."""
    data = yaml.safe_load(SIM.read_text())
    for kind in ("primitive", "service"):
        for e in data[kind]:
            e["path"] = str((SIM.parent / e["path"]).resolve())
    if callable(edit):
        edit(data)
    out = tmp_path / "deploy.yaml"
    out.write_text(yaml.safe_dump(data, sort_keys=False))
    return out


def typo(data: dict) -> None:
    data["primitive"][0]["config"]["odom_nosie"] = data["primitive"][0]["config"].pop("odom_noise")
    data["servce"] = data.pop("service")[:1]
    data["service"] = []


def test_example_configs_pass(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["validate", "-f", str(sim_copy(tmp_path))]) == 0
    assert "all packages and configs valid" in capsys.readouterr().out


def test_typo_in_config_and_top_level_key_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = sim_copy(tmp_path, typo)
    for argv in (["validate", str(path)], ["validate", "-f", str(path)]):
        assert main(argv) == 2
        out = capsys.readouterr()
        assert f"{path}: servce: unknown key (did you mean 'service'?)" in out.out
        assert f"{path}: primitive[0] (panda_mobile).config.odom_nosie: unknown field" in out.out
        assert "Traceback" not in out.out + out.err


def test_boot_refuses_bad_config_before_starting(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = sim_copy(tmp_path, lambda d: d["service"][1]["config"].update(action_wait_s=-1))
    logs = tmp_path / "logs"
    assert main(["boot", "-f", str(path), "--log-dir", str(logs)]) == 2
    err = capsys.readouterr().err
    assert f"{path}: service[1] (nav2).config.action_wait_s:" in err
    assert not logs.exists()  # nothing was started


def test_entry_keys_are_checked_too(tmp_path: Path) -> None:
    path = sim_copy(tmp_path, lambda d: d["service"][0].update(confg={"mode": "mapping"}))
    with pytest.raises(ManifestProblems) as exc:
        load_deploy(path, base_env={})
    assert exc.value.lines == [f"{path}: service[0].confg: unknown key (did you mean 'config'?)"]


def test_package_without_schema_is_not_checked(tmp_path: Path) -> None:
    """A robonix package written elsewhere declares no configSchema: its config is CMD_INIT's business."""
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "package_manifest.yaml").write_text(
        "manifestVersion: 1\npackage: {name: p, version: '1', description: d, license: MIT}\nstart: 'true'\n")
    d = tmp_path / "d.yaml"
    d.write_text("manifestVersion: 1\nname: x\nservice:\n  - {name: p, path: pkg, config: {anything: 1}}\n")
    dep = load_deploy(d, base_env={}, check_configs=True)
    assert dep.warnings == []


def test_unloadable_schema_is_a_warning(tmp_path: Path) -> None:
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "package_manifest.yaml").write_text(
        "manifestVersion: 1\npackage: {name: p, version: '1', description: d, license: MIT}\nstart: 'true'\n"
        "configSchema: no_such_module_xyz.config:parse\n")
    d = tmp_path / "d.yaml"
    d.write_text("manifestVersion: 1\nname: x\nservice:\n  - {name: p, path: pkg}\n")
    dep = load_deploy(d, base_env={}, check_configs=True)
    assert len(dep.warnings) == 1
    assert "not checked: cannot load configSchema" in dep.warnings[0]


def test_schema_from_an_uninstalled_checkout(tmp_path: Path) -> None:
    """The schema module is imported from the package's own folder when it is not installed."""
    pkg = tmp_path / "mypkg_fc"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "cfg.py").write_text("def check(c):\n    if 'rate' in c and c['rate'] <= 0:\n"
                                "        raise ValueError('rate: must be > 0')\n")
    (pkg / "package_manifest.yaml").write_text(
        "manifestVersion: 1\npackage: {name: p, version: '1', description: d, license: MIT}\nstart: 'true'\n"
        "configSchema: mypkg_fc.cfg:check\n")
    d = tmp_path / "d.yaml"
    d.write_text("manifestVersion: 1\nname: x\nservice:\n  - {name: p, path: mypkg_fc, config: {rate: 0}}\n")
    with pytest.raises(ManifestProblems) as exc:
        load_deploy(d, base_env={}, check_configs=True)
    assert exc.value.lines == [f"{d}: service[0] (p).config.rate: must be > 0"]
