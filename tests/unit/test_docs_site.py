"""The documentation: the generated pages are current, the mkdocs site builds with --strict, every shell
block of README.md and docs/ says how it is tested (tests/support/doc_blocks.py), and the README stays a
short page whose second Quick start command is what .ci/run runs."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from mkdocs.commands.build import build
from mkdocs.config import load_config
from support.doc_blocks import REPO, all_blocks, mark_problems, run_mode, shell_blocks

from rbnx import docgen

README = REPO / "README.md"


def test_generated_pages_are_current() -> None:
    stale = [str(p.relative_to(REPO)) for p in docgen.stale()]
    assert not stale, f"stale generated pages {stale}: run python -m rbnx.docgen --write"


def test_every_deploy_key_is_documented() -> None:
    assert docgen.undocumented_deploy_keys() == [], "add the keys to rbnx.docgen.DEPLOY_DOCS"


def test_cli_reference_lists_every_command() -> None:
    from rbnx.cli import build_parser

    page = (REPO / "docs" / "reference" / "cli.md").read_text()
    commands = [name for name, _ in docgen._subcommands(build_parser())]
    assert commands, "no subcommand found in the parser"
    for name in commands:
        assert f"## rbnx {name}\n" in page


def test_site_builds_strict(tmp_path: Path) -> None:
    config = load_config(str(REPO / "mkdocs.yml"), site_dir=str(tmp_path / "site"), strict=True)
    build(config)  # strict: a warning (a broken link or anchor, a missing nav page) raises
    assert (tmp_path / "site" / "index.html").is_file()
    assert (tmp_path / "site" / "reference" / "cli.html").is_file()


def test_every_shell_block_is_run_or_names_its_test() -> None:
    blocks = all_blocks()
    assert len(blocks) >= 10, "the parser found too few shell blocks"
    problems = [p for b in blocks for p in mark_problems(b)]
    assert not problems, "\n".join(problems)
    assert any(run_mode(b) for b in blocks), "no block is run for real"


def test_an_unmarked_or_dangling_block_is_reported(tmp_path: Path) -> None:
    page = tmp_path / "page.md"
    page.write_text("```bash\nrbnx caps\n```\n\n<!-- doc-test: covered-by tests/nope.py (long) -->\n"
                    "```sh\nrbnx boot\n```\n\n<!-- doc-test: covered-by tests/unit/test_docs_site.py::nope (x) -->\n"
                    "```console\nrbnx x\n```\n\n<!-- doc-test: run -->\n```bash\nrbnx --help\n```\n")
    blocks = [b.__class__(REPO / "x.md", b.line, b.text, b.mark) for b in shell_blocks(page)]
    problems = [p for b in blocks for p in mark_problems(b)]
    assert len(problems) == 3, problems
    assert "without a <!-- doc-test" in problems[0]
    assert "tests/nope.py does not exist" in problems[1]
    assert "::nope does not exist" in problems[2]


def test_readme_is_short() -> None:
    assert len(README.read_text().splitlines()) <= 250


@pytest.mark.parametrize("path", [REPO / "README.md", REPO / "docs" / "getting-started.md"])
def test_second_quick_start_command_is_what_ci_runs(path: Path) -> None:
    """The install and test parts of the README's second command appear verbatim in .ci/run."""
    text = path.read_text()
    (second,) = [line for line in text.splitlines() if line.startswith("python3 -m venv") and "[test]" in line]
    ci = (REPO / ".ci" / "run").read_text()
    for part in re.split(r"\s*&&\s*", second):
        assert part in ci, f".ci/run does not run {part!r} of the Quick start"
