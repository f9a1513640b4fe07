"""Publish-time shape/type checks, so a bad message fails in the caller with the field named.

cyclonedds' own serializer reports mistakes as a bare ``Exception("Failed to encode member …")`` or an
``AssertionError`` deep inside; we check first and raise ``TypeError``/``ValueError`` with a dotted path
(``Odometry.pose.covariance``). Checkers are built once per type from its serializer machines.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from cyclonedds.idl._machinery import InstanceMachine, PrimitiveMachine, SequenceMachine, StringMachine
from cyclonedds.idl.types import _type_code_align_size_default_mapping

from robonix_api.dds._fastpath import NumpyArrayMachine, NumpySequenceMachine

Checker = Callable[[Any, str], None]
_INT_RANGES = {"b": (-(2**7), 2**7 - 1), "B": (0, 2**8 - 1), "h": (-(2**15), 2**15 - 1), "H": (0, 2**16 - 1),
               "i": (-(2**31), 2**31 - 1), "I": (0, 2**32 - 1), "q": (-(2**63), 2**63 - 1), "Q": (0, 2**64 - 1)}
_cache: dict[type, list[tuple[str, Checker]]] = {}


def _is_bool(v: Any) -> bool:
    return isinstance(v, bool | np.bool_)


def _primitive(code: str) -> Checker:
    if code in ("f", "d"):
        def check_float(v: Any, path: str) -> None:
            if _is_bool(v) or not isinstance(v, int | float | np.integer | np.floating):
                raise TypeError(f"{path}: expected a float, got {type(v).__name__} {v!r:.60}")
        return check_float
    lo, hi = _INT_RANGES.get(code, (None, None))

    def check_int(v: Any, path: str) -> None:
        if _is_bool(v) or not isinstance(v, int | np.integer):
            raise TypeError(f"{path}: expected an integer, got {type(v).__name__} {v!r:.60}")
        if lo is not None and not lo <= int(v) <= hi:
            raise ValueError(f"{path}: {v} out of range [{lo}, {hi}]")
    return check_int


def _numeric_array(m: NumpyArrayMachine | NumpySequenceMachine) -> Checker:
    code, length = m.code, getattr(m, "length", None)
    want_float = code in ("f", "d")

    def check_array(v: Any, path: str) -> None:
        if isinstance(v, str | bytes):
            raise TypeError(f"{path}: expected a sequence of numbers, got {type(v).__name__}")
        try:
            arr = np.asarray(v)
        except (ValueError, TypeError) as exc:
            raise TypeError(f"{path}: not a numeric sequence: {exc}") from None
        kind = arr.dtype.kind
        if kind not in ("f", "i", "u") or (kind == "f" and not want_float):
            raise TypeError(f"{path}: expected {'float' if want_float else 'integer'} elements, "
                            f"got dtype {arr.dtype}")
        if arr.ndim != 1:
            raise ValueError(f"{path}: expected a 1-D sequence, got shape {arr.shape}")
        if length is not None and arr.size != length:
            raise ValueError(f"{path}: fixed array needs exactly {length} elements, got {arr.size}")
        if not want_float and arr.size and arr.dtype != m.dtype.newbyteorder("="):
            lo, hi = _INT_RANGES[code]
            if int(arr.min()) < lo or int(arr.max()) > hi:
                raise ValueError(f"{path}: values out of range [{lo}, {hi}] for dtype {m.dtype.name}")
    return check_array


def _struct_checker(t: type) -> Checker:
    def check_struct(v: Any, path: str) -> None:
        if not isinstance(v, t):
            raise TypeError(f"{path}: expected {t.__name__}, got {type(v).__name__}")
        for name, chk in _fields(t):
            chk(getattr(v, name, None), f"{path}.{name}")
    return check_struct


def _for_machine(m: Any) -> Checker:
    if isinstance(m, NumpyArrayMachine | NumpySequenceMachine):
        return _numeric_array(m)
    if isinstance(m, PrimitiveMachine):
        return _primitive(_type_code_align_size_default_mapping[m.type][0])
    if isinstance(m, StringMachine):
        def check_str(v: Any, path: str) -> None:
            if not isinstance(v, str):
                raise TypeError(f"{path}: expected str, got {type(v).__name__}")
        return check_str
    if isinstance(m, InstanceMachine):
        return _struct_checker(m.type)
    if isinstance(m, SequenceMachine):
        sub = _for_machine(m.submachine)

        def check_seq(v: Any, path: str) -> None:
            if not isinstance(v, list | tuple):
                raise TypeError(f"{path}: expected a list, got {type(v).__name__}")
            for i, item in enumerate(v):
                sub(item, f"{path}[{i}]")
        return check_seq
    return lambda v, path: None  # anything else: leave it to the serializer


def _fields(t: type) -> list[tuple[str, Checker]]:
    if t not in _cache:
        t.__idl__.populate()
        _cache[t] = [(n, _for_machine(m)) for n, m in t.__idl__.v1_machine.members_machines.items()]
    return _cache[t]


def validate_message(msg: Any, msg_type: type | None = None) -> None:
    """Raise TypeError/ValueError naming the first bad field; None when the message is well-formed."""
    t = msg_type or type(msg)
    _struct_checker(t)(msg, t.__name__)
