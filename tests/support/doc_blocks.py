"""The shell blocks of README.md and docs/**/*.md, and the comment that says how each one is tested.

Convention (docs/development.md, "Commands in the documentation"): the line right before every fenced
``bash``/``sh``/``shell``/``console`` block is one of

    <!-- doc-test: run -->                 tests/integration/docs runs the block for real (bash -e, repo root)
    <!-- doc-test: run with-atlas -->      the same, with an atlas running and ROBONIX_ATLAS pointing at it
    <!-- doc-test: covered-by TARGET [TARGET ...] (why it is not run here) -->

where TARGET is a file (``tests/.../test_x.py``, ``.ci/run``) or a test (``tests/.../test_x.py::test_name``)
that exercises the commands instead, and the reason says what they need (hardware, root, a booted robot,
minutes of running). A shell block without such a line fails tests/unit/test_doc_blocks.py.
"""

from __future__ import annotations

import ast
import re
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
SHELL_LANGS = frozenset({"bash", "sh", "shell", "console"})
_FENCE = re.compile(r"^(\s*)(```+)\s*([\w+-]*)\s*$")
_MARK = re.compile(r"^\s*<!--\s*doc-test:\s*(.*?)\s*-->\s*$")
_COVERED = re.compile(r"^covered-by\s+(?P<targets>[^()]+?)\s*\((?P<why>[^)]+)\)$")


@dataclass(frozen=True)
class Block:
    """One fenced shell block: where it is, its text, and its doc-test mark ('' when there is none)."""

    path: Path
    line: int
    text: str
    mark: str

    @property
    def where(self) -> str:
        return f"{self.path.relative_to(REPO)}:{self.line}"


def doc_files() -> list[Path]:
    """README.md and every page of the documentation site."""
    return [REPO / "README.md", *sorted((REPO / "docs").rglob("*.md"))]


def shell_blocks(path: Path) -> list[Block]:
    """Every fenced shell block of one Markdown file, with the doc-test mark on the line before it."""
    lines = path.read_text().splitlines()
    out: list[Block] = []
    i = 0
    while i < len(lines):
        m = _FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        indent, fence, lang = m.groups()
        end = i + 1
        while end < len(lines) and lines[end].strip() != fence:
            end += 1
        if lang in SHELL_LANGS:
            prev = lines[i - 1] if i > 0 else ""
            mark = _MARK.match(prev)
            body = "\n".join(x.removeprefix(indent) for x in lines[i + 1:end])
            out.append(Block(path, i + 1, body, mark.group(1) if mark else ""))
        i = end + 1
    return out


def all_blocks() -> list[Block]:
    """The shell blocks of every documentation file."""
    return [b for p in doc_files() for b in shell_blocks(p)]


def run_mode(block: Block) -> str | None:
    """'plain' or 'with-atlas' for a block the test runs, None for a covered-by block."""
    if block.mark == "run":
        return "plain"
    if block.mark == "run with-atlas":
        return "with-atlas"
    return None


def mark_problems(block: Block) -> list[str]:
    """Why a block's mark is missing or wrong (empty when it is fine)."""
    if run_mode(block) is not None:
        return []
    if not block.mark:
        return [f"{block.where}: shell block without a <!-- doc-test: ... --> line before it"]
    m = _COVERED.match(block.mark)
    if not m:
        return [f"{block.where}: unknown doc-test mark {block.mark!r} (run | run with-atlas | "
                "covered-by TARGET... (reason))"]
    return [f"{block.where}: {p}" for t in m.group("targets").split() if (p := target_problem(t))]


def target_problem(target: str) -> str | None:
    """None when ``target`` (a file, or file::test_function) exists, else what is missing."""
    file, _, test = target.partition("::")
    path = REPO / file
    if not path.is_file():
        return f"covered-by target {file} does not exist"
    if not test:
        return None
    tree = ast.parse(path.read_text())
    names = {n.name for n in ast.walk(tree) if isinstance(n, ast.FunctionDef | ast.AsyncFunctionDef)}
    return None if test in names else f"covered-by test {target} does not exist"
