"""The contract catalogue: robonix contract TOML files, and the naming rules derived from them.

One place knows how a contract id maps to its gRPC service/method and its proto message types, so
the codegen, the atlas and the SDK always agree (robonix's ``contract_gen.rs`` rules, spec §2.2).
"""

from __future__ import annotations

import os
import tomllib
from dataclasses import dataclass
from pathlib import Path

from robonix_nav_data import resources

MODES = (
    "rpc",
    "topic_out",
    "topic_in",
    "rpc_server_stream",
    "rpc_client_stream",
    "rpc_bidirectional_stream",
)
KINDS = ("primitive", "service", "skill")

#: The catalogue shipped with this project (``atlas/contracts``).
BUILTIN_ROOT = resources.contracts_root()


class ContractError(ValueError):
    """A contract TOML file is malformed; the message names the file and the key."""


@dataclass(frozen=True)
class ContractSpec:
    """One contract of the TOML catalogue (robonix's format): id, kind, mode, IDL type and its docs."""
    id: str
    version: str
    kind: str
    mode: str
    idl: str
    description: str = ""
    cross_namespace: bool = False
    source_toml_path: str = ""

    @property
    def ros_pkg(self) -> str:
        """ROS package = the directory above ``msg/`` or ``srv/`` in the idl path."""
        parts = Path(self.idl).parts
        return parts[-3] if len(parts) >= 3 else parts[0]

    @property
    def type_name(self) -> str:
        """The .msg/.srv stem, e.g. ``Navigate`` or ``Odometry``."""
        return Path(self.idl).stem

    @property
    def is_srv(self) -> bool:
        """Whether the contract's IDL is a ROS service (.srv) rather than a message."""
        return Path(self.idl).suffix == ".srv"

    @property
    def ros_type(self) -> str:
        """ROS type string as atlas reports it: ``<pkg>/msg/<Name>`` or ``<pkg>/srv/<Name>``."""
        return f"{self.ros_pkg}/{'srv' if self.is_srv else 'msg'}/{self.type_name}"

    @property
    def service_name(self) -> str:
        """The gRPC service that carries this contract (robonix's naming)."""
        return contract_service_name(self.id)

    @property
    def method_name(self) -> str:
        """The gRPC method: the .srv type name, else the contract's last segment in UpperCamel."""
        if self.is_srv:
            return self.type_name
        return upper_camel(self.id.rsplit("/", 1)[-1])

    @property
    def grpc_path(self) -> str:
        """The full gRPC method path, ``/robonix.contracts.<Service>/<Method>``."""
        return f"/robonix.contracts.{self.service_name}/{self.method_name}"

    @property
    def tool_name(self) -> str:
        """MCP tool name: the last segment of the contract id."""
        return self.id.rsplit("/", 1)[-1]

    def proto_types(self) -> tuple[str, str]:
        """Fully qualified proto (request, response) element types for an rpc contract."""
        base = f"robonix.{self.ros_pkg}.{self.type_name}"
        if self.is_srv:
            return f"{base}_Request", f"{base}_Response"
        return "google.protobuf.Empty", base


def upper_camel(segment: str) -> str:
    """``twist_in`` -> ``TwistIn``; only the first letter of each piece changes (robonix Rust rule)."""
    return "".join(p[:1].upper() + p[1:] for p in segment.split("_") if p)


def contract_service_name(contract_id: str) -> str:
    """``robonix/service/navigation/navigate/status`` -> ``RobonixServiceNavigationNavigateStatus``."""
    return "".join(upper_camel(seg) for seg in contract_id.split("/") if seg)


def parse_contract(path: Path) -> ContractSpec:
    """Read one contract TOML file; a ValueError names the file and the bad or missing key."""
    try:
        data = tomllib.loads(path.read_text())
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise ContractError(f"{path}: {exc}") from exc
    c = data.get("contract")
    if not isinstance(c, dict):
        raise ContractError(f"{path}: missing [contract] table")
    cid = c.get("id")
    if not isinstance(cid, str) or not cid:
        raise ContractError(f"{path}: [contract] id is required")
    kind = c.get("kind", "")
    if kind and kind not in KINDS:
        raise ContractError(f"{path}: [contract] kind must be one of {KINDS}, got {kind!r}")
    mode = (data.get("mode") or {}).get("type", "")
    if mode not in MODES:
        raise ContractError(f"{path}: [mode] type must be one of {MODES}, got {mode!r}")
    idl = c.get("idl", "")
    if not idl:
        legacy = (data.get("io") or {}).get("srv") or (data.get("io") or {}).get("msg") or {}
        legacy_name = legacy.get("srv") or legacy.get("msg") if isinstance(legacy, dict) else None
        if legacy_name:  # legacy `msg = "nav_msgs/msg/OccupancyGrid"` form
            idl = legacy_name + (".srv" if "/srv/" in legacy_name else ".msg")
    if not idl:
        raise ContractError(f"{path}: [contract] idl is required")
    return ContractSpec(
        id=cid,
        version=str(c.get("version", "1")),
        kind=kind or "service",
        mode=mode,
        idl=idl,
        description=str(c.get("description", "")),
        cross_namespace=bool(c.get("cross_namespace", False)),
        source_toml_path=str(path),
    )


def catalogue_roots() -> list[Path]:
    """Roots from ``ROBONIX_ATLAS_CAPABILITIES`` (comma separated), else the built-in catalogue."""
    env = os.environ.get("ROBONIX_ATLAS_CAPABILITIES") or os.environ.get("ROBONIX_CAPABILITIES")
    roots = [Path(p) for p in env.split(",") if p.strip()] if env else []
    return roots or [BUILTIN_ROOT]


def load_catalogue(roots: list[Path] | None = None) -> dict[str, ContractSpec]:
    """All contracts under the roots (``lib/`` directories skipped; a later root wins), by id."""
    out: dict[str, ContractSpec] = {}
    for root in roots or catalogue_roots():
        for path in sorted(Path(root).rglob("*.toml")):
            if "lib" in path.relative_to(root).parts:
                continue
            spec = parse_contract(path)
            out[spec.id] = spec
    return dict(sorted(out.items()))


_BUILTIN: dict[str, ContractSpec] | None = None


def builtin_contract(contract_id: str) -> ContractSpec:
    """Look up a contract of the shipped catalogue; KeyError names the id."""
    global _BUILTIN
    if _BUILTIN is None:
        _BUILTIN = load_catalogue([BUILTIN_ROOT])
    try:
        return _BUILTIN[contract_id]
    except KeyError:
        raise KeyError(f"unknown contract {contract_id!r} (not in {BUILTIN_ROOT})") from None
