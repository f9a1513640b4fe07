"""Bounded YAML for user files (deploy files, package manifests): size, nesting and alias expansion limits.

``yaml.safe_load`` is safe against code execution but not against resource abuse: a 1 kB "billion laughs"
file (aliases of aliases) expands to ~10^9 nodes and takes gigabytes, and a few thousand nested ``[`` or
indentation levels end in a RecursionError traceback. Here the text is scanned first (PyYAML's scanner is
iterative) to bound the nesting, then composed into nodes (aliases stay shared references, so this is
cheap) and the size the document *would* have with every alias expanded is counted before anything is
constructed. Each limit is a :class:`YamlLimitError` whose message says which one and by how much.
"""

from __future__ import annotations

from typing import Any

import yaml

#: A deploy file or manifest is a few kB; 1 MiB leaves room for large inline configs.
MAX_BYTES = 1 << 20
#: Deploy file (4 levels to an entry's config) + the 32 levels CMD_INIT's config_json allows + slack.
MAX_DEPTH = 48
#: Nodes after alias expansion: far above any real file, far below what hurts.
MAX_NODES = 200_000

_OPEN = (yaml.BlockMappingStartToken, yaml.BlockSequenceStartToken, yaml.FlowMappingStartToken,
         yaml.FlowSequenceStartToken)
_CLOSE = (yaml.BlockEndToken, yaml.FlowMappingEndToken, yaml.FlowSequenceEndToken)


class YamlLimitError(ValueError):
    """The text is valid YAML but exceeds one of the limits; the message names it."""


def _check_depth(text: str, max_depth: int) -> None:
    """Bound the nesting on the token stream, before the (recursive) composer sees it."""
    depth = 0
    for token in yaml.scan(text, Loader=yaml.SafeLoader):
        if isinstance(token, _OPEN):
            depth += 1
            if depth > max_depth:
                line = token.start_mark.line + 1
                raise YamlLimitError(f"line {line}: nested deeper than {max_depth} levels")
        elif isinstance(token, _CLOSE):
            depth -= 1


def expanded_size(root: yaml.Node, limit: int) -> int:
    """Node count with every alias expanded (shared nodes counted each time they are used), computed
    without recursion and without expanding; stops counting past ``limit``."""
    size: dict[int, int] = {}
    open_: set[int] = set()  # nodes whose children are being counted: meeting one again is a cycle
    stack: list[tuple[yaml.Node, bool]] = [(root, False)]
    while stack:
        node, children_done = stack.pop()
        if id(node) in size:
            continue
        if not children_done and id(node) in open_:
            raise YamlLimitError("recursive alias (a node that contains itself)")
        kids: list[yaml.Node] = []
        if isinstance(node, yaml.SequenceNode):
            kids = list(node.value)
        elif isinstance(node, yaml.MappingNode):
            kids = [n for pair in node.value for n in pair]
        if children_done or not kids:
            total = 1 + sum(size.get(id(k), 0) for k in kids)
            size[id(node)] = min(total, limit + 1)
            open_.discard(id(node))
            continue
        open_.add(id(node))
        stack.append((node, True))
        stack.extend((k, False) for k in kids if id(k) not in size)
    return size[id(root)]


def load(text: str, *, max_bytes: int = MAX_BYTES, max_depth: int = MAX_DEPTH, max_nodes: int = MAX_NODES) -> Any:
    """``yaml.safe_load`` within the limits; YamlLimitError when over one, yaml.YAMLError when invalid."""
    size = len(text.encode("utf-8", "surrogatepass"))
    if size > max_bytes:
        raise YamlLimitError(f"file too large ({size} bytes, at most {max_bytes})")
    _check_depth(text, max_depth)
    loader = yaml.SafeLoader(text)
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        nodes = expanded_size(node, max_nodes)
        if nodes > max_nodes:
            raise YamlLimitError(f"aliases expand to more than {max_nodes} nodes (an alias bomb?)")
        return loader.construct_document(node)
    finally:
        loader.dispose()
