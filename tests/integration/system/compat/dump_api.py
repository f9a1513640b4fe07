"""Prints the public API surface of whichever ``robonix_api`` is importable, as JSON.

Run once with robonix-api 0.1.0rc1's python and once with this project's; the conformance test checks
that every name of the first exists in the second with a call-compatible signature. Covered: the
modules robonix-api ships (public functions, classes and their public methods/properties, enums,
upper-case constants), the ``ATLAS`` object's methods, and dataclass constructors.
"""

import enum
import importlib
import inspect
import json
import logging
import sys
import types

MODULES = ("robonix_api", "robonix_api.atlas", "robonix_api.atlas_types", "robonix_api.capability",
           "robonix_api.codegen", "robonix_api.lifecycle", "robonix_api.result", "robonix_api.ros",
           "robonix_api.spawn", "robonix_api.tool")


def params(fn):
    try:
        sig = inspect.signature(fn)
    except (TypeError, ValueError):
        return None
    return [[p.name, p.kind.name, p.default is not inspect.Parameter.empty,
             repr(p.default) if p.default is not inspect.Parameter.empty else ""] for p in sig.parameters.values()]


def describe_class(cls, root):
    out = {}
    if issubclass(cls, enum.Enum):
        out[root] = {"type": "enum", "members": {m.name: m.value for m in cls}}
        return out
    out[root] = {"type": "class", "params": params(cls)}
    for name in dir(cls):
        if name.startswith("_"):
            continue
        owner = next((k for k in cls.__mro__ if name in vars(k)), None)
        if owner is None or owner is object or not owner.__module__.startswith("robonix_api"):
            continue
        attr = vars(owner)[name]
        if isinstance(attr, property):
            out[f"{root}.{name}"] = {"type": "property"}
        elif isinstance(attr, (staticmethod, classmethod)):
            out[f"{root}.{name}"] = {"type": "function", "params": params(getattr(cls, name))}
        elif callable(attr):
            out[f"{root}.{name}"] = {"type": "function", "params": params(attr)}
    return out


def main():
    surface = {}
    for modname in MODULES:
        try:
            mod = importlib.import_module(modname)
        except ImportError as exc:
            surface[modname] = {"type": "missing-module", "error": str(exc)}
            continue
        surface[modname] = {"type": "module"}
        exported = set(getattr(mod, "__all__", ()))
        for name in sorted(set(vars(mod)) | exported):
            obj = getattr(mod, name)  # (a module __getattr__ may provide an exported name lazily)
            if name.startswith("_") or isinstance(obj, (types.ModuleType, logging.Logger, bool)):
                continue
            own = getattr(obj, "__module__", None) == modname
            key = f"{modname}.{name}"
            if inspect.isclass(obj) and (own or name in exported):
                surface.update(describe_class(obj, key))
            elif callable(obj) and (own or name in exported):
                surface[key] = {"type": "function", "params": params(obj)}
            elif name in exported or (name.isupper() and isinstance(obj, (int, str, float))):
                if isinstance(obj, (int, str, float)):
                    surface[key] = {"type": "value", "value": obj}
                elif isinstance(obj, types.UnionType) or hasattr(obj, "__args__"):
                    surface[key] = {"type": "union", "args": sorted(a.__name__ for a in obj.__args__)}
                else:  # an object such as ATLAS: its public methods
                    surface.update(describe_class(type(obj), key))
                    surface[key] = {"type": "object"}
    json.dump(surface, sys.stdout, indent=None, sort_keys=True)


if __name__ == "__main__":
    main()
