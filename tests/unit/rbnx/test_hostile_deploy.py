"""Hostile deploy files: each is refused by ``rbnx validate`` with exit 2 and one line per problem, quickly
and in bounded memory, never a traceback (issue 37 item 10)."""

from __future__ import annotations

import io
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import pytest

from rbnx.cli import main
from rbnx.safe_yaml import MAX_NODES, YamlLimitError, expanded_size, load

PKG = "manifestVersion: 1\npackage: {name: p, version: '1', description: d, license: MIT}\nstart: 'true'\n"


def validate(tmp_path: Path, text: str) -> tuple[int, list[str]]:
    (tmp_path / "pkg").mkdir(exist_ok=True)
    (tmp_path / "pkg" / "package_manifest.yaml").write_text(PKG)
    path = tmp_path / "deploy.yaml"
    path.write_text(text)
    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        code = main(["validate", str(path)])
    assert "Traceback" not in out.getvalue() + err.getvalue()
    return code, out.getvalue().splitlines()


def entry(name: str = "p", config: str = "{}") -> str:
    return f"manifestVersion: 1\nname: x\nservice:\n  - name: {name}\n    path: pkg\n    config: {config}\n"


def test_valid_baseline(tmp_path: Path) -> None:
    assert validate(tmp_path, entry())[0] == 0


@pytest.mark.parametrize("name", ["../../../x", "a/b", ".hidden", "-rf", "x" * 65, "n" * 100_000])
def test_entry_names_are_safe_and_short(tmp_path: Path, name: str) -> None:
    """Names become <log-dir>/<name>.log: ``../../../x`` wrote outside --log-dir."""
    code, lines = validate(tmp_path, entry(name=f"'{name}'"))
    assert code == 2
    assert len(lines) == 1
    assert "service[0].name:" in lines[0]
    assert len(lines[0]) < 400  # the 100 000-character name is not echoed back whole


def test_deploy_name_is_bounded(tmp_path: Path) -> None:
    code, lines = validate(tmp_path, entry().replace("name: x", "name: " + "n" * 100_000))
    assert code == 2
    assert lines[0].endswith("name: string should have at most 256 characters")


def test_billion_laughs_in_a_config_is_refused(tmp_path: Path) -> None:
    """Nine levels of nine aliases: ~10^9 nodes once expanded (it took validate to 2 GB)."""
    bomb = "a0: &a0 [lol, lol, lol, lol, lol, lol, lol, lol, lol]\n" + "".join(
        f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 9)}]\n" for i in range(1, 10))
    text = entry(config="*a9").replace("service:", bomb + "service:")
    code, lines = validate(tmp_path, text)
    assert code == 2
    assert lines == [f"{tmp_path / 'deploy.yaml'}: refused: aliases expand to more than {MAX_NODES} nodes "
                     "(an alias bomb?)"]


@pytest.mark.parametrize("nested", ["[" * 5000 + "]" * 5000, "{a: " * 5000 + "1" + "}" * 5000])
def test_deep_config_is_one_line(tmp_path: Path, nested: str) -> None:
    """A 5000-deep config ended in a RecursionError traceback."""
    code, lines = validate(tmp_path, entry(config=nested))
    assert code == 2
    assert len(lines) == 1
    assert "refused: line 6: nested deeper than 48 levels" in lines[0]


def test_deep_block_indentation_is_one_line(tmp_path: Path) -> None:
    deep = "".join(" " * i + f"k{i}:\n" for i in range(1200)) + " " * 1200 + "v: 1\n"  # ~0.7 MB, 1200 deep
    code, lines = validate(tmp_path, deep)
    assert code == 2
    assert "nested deeper than 48 levels" in lines[0]


def test_huge_file_is_refused(tmp_path: Path) -> None:
    code, lines = validate(tmp_path, entry() + "# " + "x" * (2 << 20) + "\n")
    assert code == 2
    assert "refused: file too large" in lines[0]


@pytest.mark.parametrize("version", [0, 2, 99])
def test_unknown_manifest_version_is_refused(tmp_path: Path, version: int) -> None:
    code, lines = validate(tmp_path, entry().replace("manifestVersion: 1", f"manifestVersion: {version}"))
    assert code == 2
    assert len(lines) == 1
    assert "manifestVersion:" in lines[0]


def test_unknown_package_manifest_version_is_refused(tmp_path: Path) -> None:
    (tmp_path / "pkg").mkdir()
    (tmp_path / "pkg" / "package_manifest.yaml").write_text(PKG.replace("manifestVersion: 1", "manifestVersion: 99"))
    out = io.StringIO()
    with redirect_stdout(out), redirect_stderr(io.StringIO()):
        assert main(["validate", str(tmp_path / "pkg")]) == 2
    assert "manifestVersion: version 99 is not supported by this rbnx (it reads 1); upgrade rbnx" in out.getvalue()


def test_loader_keeps_ordinary_aliases_and_refuses_cycles() -> None:
    assert load("a: &x {b: 1}\nc: *x\nd: [*x, *x]") == {"a": {"b": 1}, "c": {"b": 1}, "d": [{"b": 1}, {"b": 1}]}
    with pytest.raises(YamlLimitError, match="recursive alias"):
        load("a: &x [1, *x]")
    assert load("") is None


def test_expanded_size_counts_shared_nodes_once_per_use() -> None:
    import yaml

    node = yaml.compose("a: &x [1, 2]\nb: [*x, *x, *x]")
    # mapping 1 + keys 2 + list x (3) + list b (1 + 3*3)
    assert expanded_size(node, 1000) == 1 + 2 + 3 + 10
