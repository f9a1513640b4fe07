"""Checks that package code uses only names robonix-api 0.1.0rc1 has (run with the real wheel installed).

For each file given: every ``from robonix_api[.mod] import name`` must resolve, every ``import
robonix_api.mod`` must import, and every attribute used on a ``Primitive(...)``/``Service(...)``/
``Skill(...)`` object or on ``ATLAS`` must exist on robonix-api's class. Prints one JSON object:
``{"checked": [...], "missing": [...]}``.
"""

import ast
import importlib
import json
import sys
from pathlib import Path


def check(path, checked, missing):
    tree = ast.parse(Path(path).read_text(), path)
    import robonix_api

    providers = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.split(".")[0] == "robonix_api":
            mod = importlib.import_module(node.module)
            for alias in node.names:
                checked.append(f"{node.module}.{alias.name}")
                if not hasattr(mod, alias.name):
                    missing.append(f"{path}: {node.module}.{alias.name}")
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] == "robonix_api":
                    checked.append(alias.name)
                    importlib.import_module(alias.name)
        elif (isinstance(node, ast.Assign) and isinstance(node.value, ast.Call)
              and isinstance(node.value.func, ast.Name) and node.value.func.id in ("Primitive", "Service", "Skill")):
            for target in node.targets:
                if isinstance(target, ast.Name):
                    providers[target.id] = getattr(robonix_api, node.value.func.id)
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name):
            owner = providers.get(node.value.id) or (robonix_api.ATLAS if node.value.id == "ATLAS" else None)
            if owner is None:
                continue
            checked.append(f"{node.value.id}.{node.attr}")
            if not hasattr(owner, node.attr):
                missing.append(f"{path}: {node.value.id}.{node.attr}")


def main():
    checked, missing = [], []
    for path in sys.argv[1:]:
        check(path, checked, missing)
    json.dump({"checked": sorted(set(checked)), "missing": missing}, sys.stdout)


if __name__ == "__main__":
    main()
