"""No import cycles between the project's modules.

The graph is built from the source with ``ast``: every ``import`` / ``from … import`` of a project module,
at module level and inside functions (a function-level import still runs, only later), but not those under
``if TYPE_CHECKING:`` (never executed). ``from pkg import name`` points at ``pkg.name`` when that is a module,
else at ``pkg`` itself. Generated code (``proto_gen``) is left out. A cycle is a strongly connected
component of more than one module, or a module importing itself.
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
PACKAGES = ("atlas", "robonix_api", "robonix_common", "rbnx", "hal_panda_mobile", "slam_service", "nav2_wrapper",
            "robonix_eval", "robonix_nav_data")
GENERATED = ("proto_gen",)

#: Cycles owned by another part of issue 14 and fixed on its branch (sorted module lists); delete an entry once
#: that branch is merged.
def _modules() -> dict[str, Path]:
    out = {}
    for pkg in PACKAGES:
        for path in sorted((REPO / pkg).rglob("*.py")):
            rel = path.relative_to(REPO).with_suffix("")
            if any(part in GENERATED for part in rel.parts):
                continue
            parts = rel.parts[:-1] if rel.name == "__init__" else rel.parts
            out[".".join(parts)] = path
    return out


def _runtime_nodes(tree: ast.AST) -> Iterator[ast.AST]:
    """Every node except those under ``if TYPE_CHECKING:``."""
    todo = [tree]
    while todo:
        node = todo.pop()
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            todo.extend(node.orelse)
            continue
        yield node
        todo.extend(ast.iter_child_nodes(node))


def _imports(module: str, path: Path, known: set[str]) -> set[str]:
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    found: set[str] = set()
    for node in _runtime_nodes(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")
                anchor = anchor[: len(anchor) - node.level + 1]
                base = ".".join([*anchor, base] if base else anchor)
            names = [f"{base}.{a.name}" if f"{base}.{a.name}" in known else base for a in node.names]
        else:
            continue
        for name in names:
            if any(part in GENERATED for part in name.split(".")):
                continue
            while name and name not in known:  # `import a.b.c` of a non-module attribute: nearest module
                name = name.rpartition(".")[0]
            if name:
                found.add(name)
    return found


def import_graph() -> dict[str, set[str]]:
    """Module -> the project modules it imports."""
    mods = _modules()
    known = set(mods)
    return {m: _imports(m, p, known) for m, p in mods.items()}


def cycles(graph: dict[str, set[str]]) -> list[tuple[str, ...]]:
    """Strongly connected components with a cycle (Tarjan, iterative), each as a sorted tuple."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    out: list[tuple[str, ...]] = []
    counter = 0
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            node, it = work[-1]
            nxt = next(it, None)
            if nxt is not None:
                if nxt not in index:
                    index[nxt] = low[nxt] = counter
                    counter += 1
                    stack.append(nxt)
                    on_stack.add(nxt)
                    work.append((nxt, iter(sorted(graph.get(nxt, ())))))
                elif nxt in on_stack:
                    low[node] = min(low[node], index[nxt])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                comp = []
                while True:
                    m = stack.pop()
                    on_stack.discard(m)
                    comp.append(m)
                    if m == node:
                        break
                if len(comp) > 1 or node in graph.get(node, ()):
                    out.append(tuple(sorted(comp)))
    return sorted(out)


def test_the_graph_sees_imports_of_every_kind() -> None:
    g = import_graph()
    assert "rbnx.commands.boot" in g["rbnx.commands"] or "rbnx.commands" in g["rbnx.cli"]
    assert "rbnx.boot.orchestrator" in g["rbnx.commands.boot"]       # from a.b import c (module)
    assert "robonix_common.errors" in g["robonix_api.validation"]      # from a.b import name
    assert "rbnx.dashboard.launch" in g["rbnx.commands.boot"]          # function-level import
    assert "rbnx.boot.procs" not in g["rbnx.boot.supervise"]           # under TYPE_CHECKING only
    assert not any("proto_gen" in m for m in g)


def test_cycle_finder_finds_a_planted_cycle() -> None:
    g = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}, "e": {"e"}}
    assert cycles(g) == [("a", "b", "c"), ("e",)]


def test_no_import_cycles() -> None:
    found = cycles(import_graph())
    assert not found, "import cycles:\n" + "\n".join(" <-> ".join(c) for c in found)
