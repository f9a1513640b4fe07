"""numpy-backed CDR machines for primitive sequences/arrays (the large-grid fast path).

cyclonedds' stock machines pack a ``sequence<int8>`` element by element through ``struct`` and return a
Python list: ~1 s for a 2000x2000 map. These machines write/read the same bytes with one
``tobytes``/``frombuffer`` and hand numpy arrays to the application. They replace the stock machines
inside each message type's struct machine (cyclonedds is pinned to 11.0.1; ``install`` fails loudly if
the internals it relies on change). The XTypes type information is built from the type hints, not from
the machines, so discovery and type matching are unaffected.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from cyclonedds.idl._machinery import (
    Machine,
    PlainCdrV2ArrayOfPrimitiveMachine,
    PlainCdrV2SequenceOfPrimitiveMachine,
    StructMachine,
)
from cyclonedds.idl._support import Endianness

# struct code -> numpy dtype (little-endian; byte-swapped for big-endian buffers)
_DTYPES: dict[str, str] = {
    "b": "<i1", "B": "<u1", "h": "<i2", "H": "<u2", "i": "<i4", "I": "<u4",
    "q": "<i8", "Q": "<u8", "f": "<f4", "d": "<f8", "?": "<u1",
}


class _NumpyMachine(Machine):
    """Shared part: dtype selection and contiguous little/big-endian bytes."""

    def __init__(self, orig: Any, code: str, alignment: int) -> None:
        self.orig = orig
        self.code = code
        self.dtype = np.dtype(_DTYPES[code])
        self.alignment = alignment

    def _dt(self, buffer: Any) -> np.dtype:
        return self.dtype if buffer.endianness == Endianness.Little else self.dtype.newbyteorder(">")

    def _write(self, buffer: Any, arr: np.ndarray) -> None:
        if arr.size:
            buffer.align(self.alignment)
            buffer.write_bytes(np.ascontiguousarray(arr, dtype=self._dt(buffer)).tobytes())

    def _read(self, buffer: Any, n: int) -> np.ndarray:
        if n == 0:
            return np.zeros(0, dtype=self.dtype.newbyteorder("="))
        buffer.align(self.alignment)
        dt = self._dt(buffer)
        arr = np.frombuffer(buffer._bytes, dtype=dt, count=n, offset=buffer._pos)
        buffer._pos += n * dt.itemsize
        return arr.astype(dt.newbyteorder("="), copy=True)

    def key_scan(self) -> Any:
        return self.orig.key_scan()

    def cdr_key_machine_op(self, skip: bool) -> Any:
        return self.orig.cdr_key_machine_op(skip)


class NumpySequenceMachine(_NumpyMachine):
    """``sequence<T>`` of a primitive T: uint32 length, then packed elements."""

    def serialize(self, buffer: Any, value: Any, *args: Any, **kwargs: Any) -> None:
        arr = np.asarray(value).reshape(-1)
        buffer.align(4)
        buffer.write("I", 4, arr.size)
        self._write(buffer, arr)

    def deserialize(self, buffer: Any, *args: Any, **kwargs: Any) -> np.ndarray:
        buffer.align(4)
        return self._read(buffer, buffer.read("I", 4))

    def default_initialize(self) -> np.ndarray:
        return np.zeros(0, dtype=self.dtype.newbyteorder("="))


class NumpyArrayMachine(_NumpyMachine):
    """``T[N]`` of a primitive T: exactly N packed elements, no length prefix."""

    def __init__(self, orig: Any, code: str, alignment: int, length: int) -> None:
        super().__init__(orig, code, alignment)
        self.length = length

    def serialize(self, buffer: Any, value: Any, *args: Any, **kwargs: Any) -> None:
        arr = np.asarray(value).reshape(-1)
        if arr.size != self.length:
            raise ValueError(f"fixed array needs {self.length} elements, got {arr.size}")
        self._write(buffer, arr)

    def deserialize(self, buffer: Any, *args: Any, **kwargs: Any) -> np.ndarray:
        return self._read(buffer, self.length)

    def default_initialize(self) -> np.ndarray:
        return np.zeros(self.length, dtype=self.dtype.newbyteorder("="))


def _replacement(m: Any) -> Machine | None:
    if isinstance(m, PlainCdrV2SequenceOfPrimitiveMachine) and m.code in _DTYPES:
        return NumpySequenceMachine(m, m.code, m.alignment)
    if isinstance(m, PlainCdrV2ArrayOfPrimitiveMachine):
        code = m.code.lstrip("0123456789")
        if code in _DTYPES:
            return NumpyArrayMachine(m, code, m.alignment, m.length)
    return None


def install(idl_type: type) -> None:
    """Swap the primitive sequence/array machines of one struct type for the numpy ones."""
    idl = idl_type.__idl__
    idl.populate()
    for machine in (idl.v1_machine, idl.v2_machine):
        if not isinstance(machine, StructMachine):
            raise RuntimeError(f"{idl_type.__name__}: unexpected cyclonedds machine {type(machine).__name__}; "
                               "robonix_api.dds needs cyclonedds==11.0.1")
        for name, m in list(machine.members_machines.items()):
            new = _replacement(m)
            if new is not None:
                machine.members_machines[name] = new
