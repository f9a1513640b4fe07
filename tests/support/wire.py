"""A tiny hand-written protobuf codec for wire-compatibility tests: requests are built field by field
from the spec's numbers and replies decoded the same way, never through our generated stubs."""

from __future__ import annotations

VARINT, LEN = 0, 2


def varint(n: int) -> bytes:
    out = bytearray()
    while True:
        b = n & 0x7F
        n >>= 7
        if n:
            out.append(b | 0x80)
        else:
            out.append(b)
            return bytes(out)


def tag(field: int, wire_type: int) -> bytes:
    return varint(field << 3 | wire_type)


def f_varint(field: int, n: int) -> bytes:
    return tag(field, VARINT) + varint(n)


def f_bytes(field: int, data: bytes) -> bytes:
    return tag(field, LEN) + varint(len(data)) + data


def f_str(field: int, s: str) -> bytes:
    return f_bytes(field, s.encode())


def read_varint(buf: bytes, i: int) -> tuple[int, int]:
    shift = value = 0
    while True:
        b = buf[i]
        i += 1
        value |= (b & 0x7F) << shift
        shift += 7
        if not b & 0x80:
            return value, i


def decode(buf: bytes) -> dict[int, list]:
    """field number -> list of raw values (int for varints, bytes for length-delimited)."""
    out: dict[int, list] = {}
    i = 0
    while i < len(buf):
        key, i = read_varint(buf, i)
        field, wt = key >> 3, key & 7
        if wt == VARINT:
            value, i = read_varint(buf, i)
        elif wt == LEN:
            n, i = read_varint(buf, i)
            value, i = buf[i : i + n], i + n
        elif wt == 1:
            value, i = buf[i : i + 8], i + 8
        elif wt == 5:
            value, i = buf[i : i + 4], i + 4
        else:
            raise AssertionError(f"unexpected wire type {wt}")
        out.setdefault(field, []).append(value)
    return out


def one(msg: dict[int, list], field: int, default=None):
    values = msg.get(field)
    return values[-1] if values else default
