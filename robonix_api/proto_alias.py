"""Top-level names for the bundled generated protos (``import map_pb2``), as robonix packages write them.

robonix's ``rbnx codegen`` writes ``atlas_pb2``, ``lifecycle_pb2``, ``robonix_contracts_pb2_grpc``,
``<ros package>_pb2`` ... into ``<pkg>/rbnx-build/codegen/proto_gen`` and robonix-api puts that folder
on ``sys.path``, so package code imports them as top-level modules. This SDK ships the same modules
as ``robonix_api.proto_gen.*``. A finder placed *first* on ``sys.meta_path`` answers exactly those
top-level names with the bundled modules (the very same module objects, so message classes are
identical). It must come before ``sys.path``: a package's own copy of, say, ``robonix_contracts_pb2``
would register ``robonix_contracts.proto`` a second time in protobuf's default pool, which protobuf
refuses ("duplicate file name"). A package's *other* generated modules still load from its folder.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

_GEN_DIR = Path(__file__).resolve().parent / "proto_gen"
_PACKAGE = "robonix_api.proto_gen"


def bundled_names() -> frozenset[str]:
    """Module names in the bundled ``proto_gen`` (``map_pb2``, ``robonix_contracts_pb2_grpc``, ...)."""
    return frozenset(p.stem for p in _GEN_DIR.glob("*_pb2*.py"))


class _AliasLoader(importlib.abc.Loader):
    def create_module(self, spec: importlib.machinery.ModuleSpec) -> ModuleType:
        return importlib.import_module(f"{_PACKAGE}.{spec.name}")

    def exec_module(self, module: ModuleType) -> None:  # already executed under its package name
        return None


class ProtoGenAliasFinder(importlib.abc.MetaPathFinder):
    """Resolves a bundled generated module's bare name to ``robonix_api.proto_gen.<name>``."""

    def __init__(self) -> None:
        self.names = bundled_names()

    def find_spec(self, fullname: str, path: Any = None, target: Any = None) -> importlib.machinery.ModuleSpec | None:
        """Answer ``import <name>_pb2`` for a bundled generated module (robonix packages import them top-level)."""
        if "." in fullname or fullname not in self.names:
            return None
        return importlib.machinery.ModuleSpec(fullname, _AliasLoader())


def install() -> None:
    """Put the finder first on ``sys.meta_path`` once (idempotent)."""
    if not any(isinstance(f, ProtoGenAliasFinder) for f in sys.meta_path):
        sys.meta_path.insert(0, ProtoGenAliasFinder())


__all__ = ["ProtoGenAliasFinder", "bundled_names", "install"]
