"""The atlas contract catalogue: contract TOML files turned into ``ContractDescriptor``s.

FieldSpecs come from the generated protobuf descriptors rather than from .msg/.srv sources, because
the generated stubs are what every provider actually speaks (and they are checked against the protos
by a test). Proto scalar types are mapped back to ROS primitive names; where proto widened a ROS type
(uint8 -> uint32) a small table of known fields restores the ROS name.
"""

from __future__ import annotations

import logging
from collections.abc import Iterable
from pathlib import Path

from google.protobuf import descriptor_pool
from google.protobuf.descriptor import Descriptor, FieldDescriptor

from robonix_api.contracts import ContractSpec, load_catalogue
from robonix_api.types import ContractDescriptor, FieldSpec, Kind

log = logging.getLogger(__name__)

_FD = FieldDescriptor
#: proto3 scalar -> canonical ROS primitive (the inverse of robonix's RosPrimitive::proto_type).
PROTO_TO_ROS: dict[int, str] = {
    _FD.TYPE_DOUBLE: "float64",
    _FD.TYPE_FLOAT: "float32",
    _FD.TYPE_INT64: "int64",
    _FD.TYPE_UINT64: "uint64",
    _FD.TYPE_INT32: "int32",
    _FD.TYPE_FIXED64: "uint64",
    _FD.TYPE_FIXED32: "uint32",
    _FD.TYPE_BOOL: "bool",
    _FD.TYPE_STRING: "string",
    _FD.TYPE_UINT32: "uint32",
    _FD.TYPE_ENUM: "int32",
    _FD.TYPE_SFIXED32: "int32",
    _FD.TYPE_SFIXED64: "int64",
    _FD.TYPE_SINT32: "int32",
    _FD.TYPE_SINT64: "int64",
}

#: Fields whose ROS type is narrower than the proto one (proto has no 8/16-bit ints), by full name.
ROS_TYPE_HINTS: dict[str, str] = {
    "robonix.lifecycle.Driver_Request.command": "uint8",
    "robonix.nav_msgs.OccupancyGrid.data": "int8",
}


def _ros_message_name(full_name: str) -> str:
    """``robonix.geometry_msgs.Pose`` -> ``geometry_msgs/Pose``."""
    parts = full_name.split(".")
    if len(parts) >= 3 and parts[0] == "robonix":
        return f"{parts[1]}/{'.'.join(parts[2:])}"
    return full_name.replace(".", "/")


def field_spec(fd: FieldDescriptor) -> FieldSpec:
    """One proto field as a ROS-flavoured FieldSpec (arrays have ``array_size`` 0: proto keeps no bound)."""
    repeated = bool(fd.is_repeated)
    if fd.type == FieldDescriptor.TYPE_MESSAGE:
        return FieldSpec(fd.name, _ros_message_name(fd.message_type.full_name), False, repeated, 0)
    if fd.type == FieldDescriptor.TYPE_BYTES:  # robonix maps unbounded uint8[] to bytes
        return FieldSpec(fd.name, "uint8", True, True, 0)
    ros = ROS_TYPE_HINTS.get(fd.full_name) or PROTO_TO_ROS.get(fd.type, "string")
    return FieldSpec(fd.name, ros, True, repeated, 0)


def message_fields(
    full_name: str, pool: descriptor_pool.DescriptorPool | None = None
) -> tuple[FieldSpec, ...]:
    """FieldSpecs of a generated message in declaration (= wire number) order; empty if unknown."""
    desc = _find(full_name, pool)
    if desc is None:
        return ()
    return tuple(field_spec(f) for f in sorted(desc.fields, key=lambda f: f.number))


def _find(full_name: str, pool: descriptor_pool.DescriptorPool | None) -> Descriptor | None:
    _import_generated()
    try:
        return (pool or descriptor_pool.Default()).FindMessageTypeByName(full_name)
    except KeyError:
        return None


_IMPORTED = False


def _import_generated() -> None:
    """Importing robonix_contracts_pb2 registers every per-package message in the default pool."""
    global _IMPORTED
    if not _IMPORTED:
        from robonix_api.proto_gen import robonix_contracts_pb2  # noqa: F401

        _IMPORTED = True


def build_descriptor(spec: ContractSpec) -> ContractDescriptor:
    """ContractDescriptor for one contract; a type the stubs lack gives empty field lists plus a warning."""
    kind = Kind.parse(spec.kind) if spec.kind else Kind.UNSPECIFIED
    msg_fields: tuple[FieldSpec, ...] = ()
    req: tuple[FieldSpec, ...] = ()
    resp: tuple[FieldSpec, ...] = ()
    req_name, resp_name = spec.proto_types()
    if spec.is_srv:
        if _find(req_name, None) is None or _find(resp_name, None) is None:
            log.warning("contract %s: no generated proto for %s; fields left empty", spec.id, spec.idl)
        req, resp = message_fields(req_name), message_fields(resp_name)
    else:
        if _find(resp_name, None) is None:
            log.warning("contract %s: no generated proto for %s; fields left empty", spec.id, spec.idl)
        msg_fields = message_fields(resp_name)
    return ContractDescriptor(
        id=spec.id,
        version=spec.version,
        kind=kind,
        mode=spec.mode,
        io_msg_type="" if spec.is_srv else spec.ros_type,
        io_srv_type=spec.ros_type if spec.is_srv else "",
        source_toml_path=spec.source_toml_path,
        msg_fields=msg_fields,
        srv_request_fields=req,
        srv_response_fields=resp,
        description=spec.description,
        cross_namespace=spec.cross_namespace,
    )


class Catalogue:
    """Immutable id -> ContractDescriptor map, sorted by id (ListContracts order)."""

    def __init__(self, descriptors: Iterable[ContractDescriptor] = ()) -> None:
        self._by_id = {d.id: d for d in sorted(descriptors, key=lambda d: d.id)}

    @classmethod
    def load(cls, roots: list[Path] | None = None) -> Catalogue:
        """Load the TOML files under roots (default: ``ROBONIX_ATLAS_CAPABILITIES`` or the built-in set).
        Raises ``robonix_api.contracts.ContractError`` naming the bad file."""
        return cls(build_descriptor(s) for s in load_catalogue(roots).values())

    def get(self, contract_id: str) -> ContractDescriptor | None:
        return self._by_id.get(contract_id)

    def list(self, prefix: str = "") -> list[ContractDescriptor]:
        return [d for cid, d in self._by_id.items() if cid.startswith(prefix)]

    def __contains__(self, contract_id: object) -> bool:
        return contract_id in self._by_id

    def __len__(self) -> int:
        return len(self._by_id)
