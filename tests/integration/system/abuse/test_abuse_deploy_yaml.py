"""Property-based abuse of deploy files through ``rbnx validate`` (in process): hypothesis mutates a valid
deploy (values replaced by hostile ones, keys dropped or added) and writes raw hostile YAML (broken
syntax, alias bombs, huge documents). The answer is always exit 0, or exit 2 with one line per problem:
never a traceback, never a hang."""

from __future__ import annotations

import copy
import io
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path
from typing import Any

import pytest
import yaml
from hypothesis import given
from hypothesis import strategies as st

from rbnx.cli import main as rbnx_main

from .deployment import deploy_dict
from .strategies import fuzz_settings, hostile_text, json_values

EXAMPLES = fuzz_settings(150)
BOMB = "a: &a [x, x, x, x, x, x, x, x, x]\n" + "".join(
    f"{chr(98 + i)}: &{chr(98 + i)} [*{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, "
    f"*{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}]\n" for i in range(8))
RAW = ["", "---", "\t- x", "primitive: [", "primitive: {a: 1", "manifestVersion: 99\n", "!!python/object:os.system x",
       "primitive:\n  - name: x\n    path: /etc\n", "service: 7\n", BOMB, "primitive:\n" + BOMB.replace("\n", "\n  "),
       "name: " + "n" * 200_000 + "\nprimitive: []\n", "env: {A: ${B:-${C:-${D}}}}\nprimitive: []\n",
       "system: {atlas: {listen: 'evil.example.com:443'}}\nprimitive: []\n"]
_TOUCHED: list[str] = []


def _paths(obj: Any, prefix: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    out = [prefix]
    if isinstance(obj, dict):
        for k, v in obj.items():
            out += _paths(v, prefix + (k,))
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            out += _paths(v, prefix + (i,))
    return out


@st.composite
def mutated_deploys(draw: st.DrawFn, base: dict[str, Any]) -> str:
    doc = copy.deepcopy(base)
    for _ in range(draw(st.integers(1, 3))):
        paths = [p for p in _paths(doc) if p]
        if not paths:
            break
        path = draw(st.sampled_from(paths))
        parent = doc
        for key in path[:-1]:
            parent = parent[key]
        action = draw(st.sampled_from(["replace", "replace", "drop", "add"]))
        if action == "drop":
            del parent[path[-1]]
        elif action == "add" and isinstance(parent, dict):
            parent[draw(hostile_text())] = draw(json_values(4))
        else:
            parent[path[-1]] = draw(json_values(6))
    return yaml.safe_dump(doc, sort_keys=False, allow_unicode=True)


def validate(path: Path) -> tuple[int, str]:
    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        code = rbnx_main(["validate", str(path)])
    return code, out.getvalue() + err.getvalue()


def check(path: Path, text: str) -> None:
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    code, output = validate(path)
    _TOUCHED.append(text[:40])
    assert code in (0, 2), (code, output[-2000:])
    assert "Traceback" not in output, output[-2000:]
    if code == 2:
        assert output.strip(), "exit 2 without saying why"


def test_mutated_and_raw_deploy_files(tmp_path: Path) -> None:
    maps_root = tmp_path / "maps_root"
    base = deploy_dict(maps_root)
    target = tmp_path / "deploy.yaml"
    code, output = validate(_write(target, yaml.safe_dump(base, sort_keys=False)))
    assert code == 0, output  # the unmutated deploy is valid: the mutations are what gets refused

    @EXAMPLES
    @given(text=st.one_of(mutated_deploys(base), st.sampled_from(RAW), st.text(max_size=200)))
    def run(text: str) -> None:
        check(target, text)

    run()
    print(f"rbnx validate: {len(_TOUCHED)} hostile deploy files tried")
    from .conftest import TRIED

    TRIED["rbnx validate deploy YAML"] = TRIED.get("rbnx validate deploy YAML", 0) + len(_TOUCHED)


def _write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


@pytest.mark.parametrize("text", [BOMB, "primitive:\n" + BOMB.replace("\n", "\n  ")])
def test_alias_bomb_is_refused_quickly(tmp_path: Path, text: str) -> None:
    check(tmp_path / "deploy.yaml", text)
