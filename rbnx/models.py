"""Pydantic models of the deploy file and package_manifest.yaml, and their loaders.

Loaders never raise a traceback-worthy error for user mistakes: they collect every problem as one line
`<file>: <key.path>: <message>` and raise ManifestProblems, which the CLI prints and maps to exit 2.
"""

from __future__ import annotations

import os
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from rbnx import safe_yaml
from rbnx.boot.supervise import RestartMode, RestartPolicy
from rbnx.envexpand import apply_env_section, expand_tree
from robonix_common.errors import field_path, field_problems
from robonix_common.errors import validation_lines as common_validation_lines
from robonix_nav_data import resources

KINDS: tuple[str, ...] = ("primitive", "service", "skill")
DEFAULT_ATLAS_LISTEN = "127.0.0.1:50051"
PACKAGE_MANIFEST = "package_manifest.yaml"
DEFAULT_DEPLOY = "robonix_manifest.yaml"
#: The manifestVersion values this rbnx understands (deploy files and package manifests); a newer file may
#: mean keys that change what a boot does, so it is refused rather than half-understood.
MANIFEST_VERSIONS: tuple[int, ...] = (1,)
#: Entry names become log file names, run-dir keys and atlas provider ids: a safe, short pattern only.
ENTRY_NAME_RE = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,63}")
#: Top-level keys of a deploy file (robonix's set); anything else is a typo, refused with a suggestion.
DEPLOY_KEYS: tuple[str, ...] = ("manifestVersion", "name", "env", "system", *("primitive", "service", "skill"))
#: Keys of one deploy entry (robonix's plus rbnx's supervision and autostart).
ENTRY_KEYS: tuple[str, ...] = ("name", "path", "url", "branch", "manifest", "config", "autostart",
                               "restart", "restart_max", "restart_backoff_s")


class ManifestProblems(Exception):
    """One or more problems with user files; `lines` are ready to print, one per problem."""

    def __init__(self, lines: list[str]) -> None:
        super().__init__("\n".join(lines))
        self.lines = lines


def _none_to_list(v: Any) -> Any:
    return [] if v is None else v


def _known_version(v: int) -> int:
    if v not in MANIFEST_VERSIONS:
        known = ", ".join(str(x) for x in MANIFEST_VERSIONS)
        raise ValueError(f"version {v} is not supported by this rbnx (it reads {known}); upgrade rbnx")
    return v


def unknown_key(key: str, known: tuple[str, ...]) -> str:
    """``unknown key 'servce' (did you mean 'service'?)``."""
    import difflib

    near = difflib.get_close_matches(str(key), known, n=1)
    hint = f" (did you mean {near[0]!r}?)" if near else f" (expected one of: {', '.join(known)})"
    return f"unknown key{hint}"


def _scalar_to_str(v: Any) -> Any:
    """YAML turns `version: 1.0` into a float; a version is text, so accept scalars."""
    if isinstance(v, bool):
        return v
    return str(v) if isinstance(v, int | float) else v


# ---------------------------------------------------------------- package_manifest.yaml


class PackageInfo(BaseModel):
    model_config = ConfigDict(extra="ignore")
    name: str = Field(min_length=1)
    version: str
    description: str
    license: str
    tags: list[str] = []
    maintainers: list[Any] = []

    _coerce = field_validator("version", "license", "description", mode="before")(_scalar_to_str)
    _lists = field_validator("tags", "maintainers", mode="before")(_none_to_list)

    @field_validator("name")
    @classmethod
    def _name_ok(cls, v: str) -> str:
        if not v.strip():
            raise ValueError("must not be empty")
        return v


class CapabilityRef(BaseModel):
    model_config = ConfigDict(extra="ignore")
    name: str = Field(min_length=1)
    path: str | None = None


class DependsRef(BaseModel):
    model_config = ConfigDict(extra="ignore")
    name: str = Field(min_length=1)
    path: str | None = None
    url: str | None = None
    branch: str | None = None


class PackageManifest(BaseModel):
    """package_manifest.yaml; unknown keys are ignored (robonix adds keys over time)."""

    model_config = ConfigDict(extra="ignore", populate_by_name=True)
    manifestVersion: int = Field(ge=1)
    package: PackageInfo

    _version = field_validator("manifestVersion")(_known_version)
    build: str | None = None
    start: str = Field(min_length=1)
    stop: str | None = None
    capabilities: list[CapabilityRef] = []
    depends: list[DependsRef] = []
    #: ``module:function`` that validates the CMD_INIT config (raises ValueError naming the field); read by
    #: rbnx validate/boot (rbnx/config_check.py). Ours, optional: robonix ignores unknown manifest keys.
    configSchema: str | None = Field(None, pattern=r"^[A-Za-z_][\w.]*:[A-Za-z_]\w*$", max_length=256)

    _lists = field_validator("capabilities", "depends", mode="before")(_none_to_list)

    @field_validator("start")
    @classmethod
    def _start_ok(cls, v: str) -> str:
        if not v.strip():
            raise ValueError("must not be empty")
        return v


# ---------------------------------------------------------------- deploy file


class RestartFields(BaseModel):
    """Supervision of one process by `rbnx boot` (see rbnx/boot/supervise.py): whether it is started again
    after it exits on its own, how many times in a row at most, and the first backoff delay."""

    restart: RestartMode = "never"
    restart_max: int = Field(default=5, ge=0, le=1000)
    restart_backoff_s: float = Field(default=0.5, gt=0, le=60)

    def restart_policy(self) -> RestartPolicy:
        return RestartPolicy(self.restart, self.restart_max, self.restart_backoff_s,
                             max(10.0, self.restart_backoff_s))


class AtlasSystem(RestartFields):
    model_config = ConfigDict(extra="allow")
    listen: str = DEFAULT_ATLAS_LISTEN
    log: str | None = None
    # "token": rbnx boot makes a deployment token and every change needs it; "none": robonix's open atlas
    auth: Literal["token", "none"] = "token"
    # hosts besides loopback that declared gRPC/MCP endpoints may name ("*" = any), for multi-host setups
    allowed_hosts: list[str] = Field(default_factory=list, max_length=256)

    @field_validator("allowed_hosts")
    @classmethod
    def _hosts_ok(cls, v: list[str]) -> list[str]:
        from atlas.trust import parse_allowed_hosts

        try:
            return list(parse_allowed_hosts(v))
        except ValueError as exc:  # the field is named by the caller already
            raise ValueError(str(exc).removeprefix("allowed_hosts: ")) from None

    @field_validator("listen")
    @classmethod
    def _listen_ok(cls, v: str) -> str:
        m = re.fullmatch(r"(.+):(\d{1,5})", v.strip())
        if not m or int(m.group(2)) > 65535:
            raise ValueError(f"expected HOST:PORT, got {v!r}")
        return v.strip()


class SystemSection(BaseModel):
    model_config = ConfigDict(extra="allow")
    atlas: AtlasSystem = AtlasSystem()

    _atlas = field_validator("atlas", mode="before")(lambda v: {} if v is None else v)


class DeployEntry(RestartFields):
    model_config = ConfigDict(extra="allow")
    name: str = Field(max_length=64)
    path: str | None = Field(None, max_length=4096)
    url: str | None = Field(None, max_length=4096)
    branch: str | None = None
    manifest: str | None = None
    config: dict[str, Any] = {}
    #: false: boot stops at INACTIVE and an agent (gateway) or `rbnx lifecycle` decides when it runs
    autostart: bool = True

    _cfg = field_validator("config", mode="before")(lambda v: {} if v is None else v)

    @field_validator("name")
    @classmethod
    def _name_ok(cls, v: str) -> str:
        if not v.strip():
            raise ValueError("must not be empty")
        if v != v.strip() or any(c.isspace() for c in v):
            raise ValueError(f"must not contain whitespace: {v!r}")
        if not ENTRY_NAME_RE.fullmatch(v):
            raise ValueError(f"{v!r} is not a valid name: letters, digits, '_', '.', '-' (not first), "
                             "at most 64 characters")
        return v


class DeployFile(BaseModel):
    model_config = ConfigDict(extra="allow")
    manifestVersion: int = Field(ge=1)
    name: str = Field(min_length=1, max_length=256)
    env: dict[str, Any] = {}
    system: SystemSection = SystemSection()
    primitive: list[DeployEntry] = []
    service: list[DeployEntry] = []
    skill: list[DeployEntry] = []

    _lists = field_validator("primitive", "service", "skill", mode="before")(_none_to_list)
    _version = field_validator("manifestVersion")(_known_version)
    _env = field_validator("env", mode="before")(lambda v: {} if v is None else v)
    _sys = field_validator("system", mode="before")(lambda v: {} if v is None else v)


# ---------------------------------------------------------------- helpers


#: ('service', 1, 'name') -> 'service[1].name' (the project's one formatter, robonix_common.errors).
loc_to_path = field_path


def validation_lines(label: str, exc: ValidationError) -> list[str]:
    """One ``label: path: message`` problem per pydantic error."""
    return [f"{label}: {line}" for line in common_validation_lines(exc)]


def read_yaml(path: Path, label: str | None = None) -> Any:
    """Parse YAML; a syntax error becomes one `file:line: message` problem."""
    label = label or str(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ManifestProblems([f"{label}: no such file"]) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ManifestProblems([f"{label}: cannot read: {exc}"]) from None
    try:
        return safe_yaml.load(text)
    except safe_yaml.YamlLimitError as exc:
        raise ManifestProblems([f"{label}: refused: {exc}"]) from None
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        where = f"{label}:{mark.line + 1}:{mark.column + 1}" if mark else label
        what = " ".join(str(x) for x in (exc.problem, exc.context) if x) or "invalid YAML"
        raise ManifestProblems([f"{where}: YAML syntax error: {what}"]) from None
    except yaml.YAMLError as exc:
        raise ManifestProblems([f"{label}: YAML error: {exc}"]) from None


def detect_kind(data: Any) -> Literal["deploy", "package", "unknown"]:
    """A package manifest has `package:`/`start:`; a deploy file lists entries or `system:`."""
    if not isinstance(data, dict):
        return "unknown"
    if "package" in data or "start" in data:
        return "package"
    if any(k in data for k in (*KINDS, "system")):
        return "deploy"
    return "unknown"


def manifest_file(root: Path, manifest: str | None) -> Path:
    """`manifest: jetson-docker` -> package_manifest.jetson-docker.yaml; a *.yaml value is a file name."""
    if not manifest:
        return root / PACKAGE_MANIFEST
    if manifest.endswith((".yaml", ".yml")):
        return root / manifest
    return root / f"package_manifest.{manifest}.yaml"


def parse_package(data: Any, label: str) -> PackageManifest:
    if data is None:
        raise ManifestProblems([f"{label}: empty file"])
    if not isinstance(data, dict):
        raise ManifestProblems([f"{label}: top level must be a mapping, got {type(data).__name__}"])
    try:
        return PackageManifest.model_validate(data)
    except ValidationError as exc:
        raise ManifestProblems(validation_lines(label, exc)) from None


def load_package(path: Path, manifest: str | None = None) -> tuple[Path, PackageManifest]:
    """Load a package by its root directory (or manifest file); returns (root, manifest)."""
    path = Path(path)
    if path.is_dir():
        root, mfile = path.resolve(), manifest_file(path.resolve(), manifest)
    else:
        root, mfile = path.resolve().parent, path
    if not mfile.is_file():
        raise ManifestProblems([f"{mfile}: no such package manifest"])
    return root, parse_package(read_yaml(mfile), str(mfile))


# ---------------------------------------------------------------- deploy resolution


@dataclass
class ResolvedEntry:
    """One deploy entry with its package found and validated."""

    name: str
    kind: str
    index: int
    root: Path
    manifest_path: Path
    manifest: PackageManifest
    config: dict[str, Any]
    autostart: bool = True
    restart: RestartPolicy = field(default_factory=RestartPolicy)

    @property
    def key(self) -> str:
        return f"{self.kind}[{self.index}]"


@dataclass
class ResolvedDeploy:
    path: Path
    name: str
    env: dict[str, str]
    atlas_listen: str
    atlas_log: str | None
    entries: list[ResolvedEntry]
    warnings: list[str] = field(default_factory=list)
    atlas_auth: str = "token"
    atlas_allowed_hosts: list[str] = field(default_factory=list)
    atlas_restart: RestartPolicy = field(default_factory=RestartPolicy)


def packages_dir(deploy_dir: Path, env: Mapping[str, str]) -> Path:
    """Where `url:` packages are expected as local checkouts (we never fetch)."""
    return Path(env.get("RBNX_PACKAGES_DIR") or deploy_dir / "rbnx-packages")


def _url_checkout(url: str, deploy_dir: Path, env: Mapping[str, str]) -> Path:
    base = url.rstrip("/").rsplit("/", 1)[-1].removesuffix(".git")
    return packages_dir(deploy_dir, env) / base


def _entry_root(e: DeployEntry, key: str, deploy_dir: Path, env: Mapping[str, str], label: str,
                problems: list[str]) -> Path | None:
    """The package folder of an entry (``path:`` or the local checkout of ``url:``); None and a problem
    appended when it does not exist."""
    if e.path is not None:
        root = (deploy_dir / e.path).resolve()
        if not root.is_dir():
            problems.append(f"{label}: {key}.path: no such directory {e.path!r} ({root})")
            return None
        return root
    assert e.url is not None
    root = _url_checkout(e.url, deploy_dir, env)
    if not root.is_dir():
        problems.append(f"{label}: {key}.url: cannot fetch {e.url!r} (no network access); "
                        f"clone it to {root} or use 'path:'")
        return None
    return root


def _source_problems(data: Mapping[str, Any]) -> list[tuple[tuple[Any, ...], str]]:
    """Exactly one of path/url per entry, checked on the raw data so it is reported next to field errors."""
    out: list[tuple[tuple[Any, ...], str]] = []
    for kind in KINDS:
        entries = data.get(kind)
        if not isinstance(entries, list):
            continue
        for i, e in enumerate(entries):
            if isinstance(e, dict) and (e.get("path") is None) == (e.get("url") is None):
                out.append(((kind, i), "exactly one of 'path' or 'url' must be set"))
    return out


def section_order(raw: Mapping[str, Any]) -> list[str]:
    """Entry sections in the order the file lists them (robonix's primitive, service, skill when a file
    uses that order): the file is the boot order, so a dependent may be listed first and is retried."""
    present = [k for k in raw if k in KINDS]
    return present + [k for k in KINDS if k not in present]


def _expand_deploy(raw: dict[str, Any], base_env: dict[str, str],
                   label: str) -> tuple[dict[str, Any], dict[str, str], list[str]]:
    """Apply the deploy file's ``env:`` section to ``base_env`` and expand ``${VAR}`` in every other section;
    returns the expanded document, the environment and the problems (each prefixed with ``label``)."""
    problems: list[str] = []
    env_section = raw.get("env")
    env = base_env
    if isinstance(env_section, dict):
        env_problems: list[str] = []
        env = apply_env_section(env_section, base_env, env_problems)
        problems += [f"{label}: {p}" for p in env_problems]
    expanded = {k: (v if k == "env" else expand_tree(v, env, str(k), problems)) for k, v in raw.items()}
    return expanded, env, [p if p.startswith(f"{label}: ") else f"{label}: {p}" for p in problems]


def load_deploy(path: Path, base_env: Mapping[str, str] | None = None, label: str | None = None,
                check_configs: bool = False) -> ResolvedDeploy:
    """Parse, expand, validate a deploy file and every package it references; all problems at once.

    ``check_configs``: also check each entry's config against its package's ``configSchema`` (what
    ``rbnx validate`` and ``rbnx boot`` do; see rbnx/config_check.py)."""
    path = Path(path)
    label = label or str(path)
    base_env = dict(os.environ if base_env is None else base_env)
    base_env.setdefault(resources.DATA_ROOT_ENV, str(resources.data_root()))  # what `rbnx init` copies name
    raw = read_yaml(path, label)
    if raw is None:
        raise ManifestProblems([f"{label}: empty file"])
    if not isinstance(raw, dict):
        raise ManifestProblems([f"{label}: top level must be a mapping, got {type(raw).__name__}"])

    expanded, env, problems = _expand_deploy(raw, base_env, label)
    found = _source_problems(expanded)
    try:
        model = DeployFile.model_validate(expanded)
    except ValidationError as exc:
        found += field_problems(exc)
    if found:
        order = {k: i for i, k in enumerate(expanded)}
        found.sort(key=lambda lm: (order.get(lm[0][0], -1) if lm[0] else -1,
                                   lm[0][1] if len(lm[0]) > 1 and isinstance(lm[0][1], int) else -1))
        raise ManifestProblems(problems + [f"{label}: {loc_to_path(loc)}: {m}" for loc, m in found])
    if problems:  # unexpanded paths would only add follow-on noise
        raise ManifestProblems(problems)

    # A misspelt key (``servce:``) silently ignored would boot a different system than the file describes.
    problems += [f"{label}: {k}: {unknown_key(k, DEPLOY_KEYS)}" for k in (model.model_extra or {})]
    warnings: list[str] = []
    deploy_dir = path.resolve().parent
    seen: dict[str, str] = {}
    entries: list[ResolvedEntry] = []
    for kind in section_order(raw):
        for i, e in enumerate(getattr(model, kind)):
            key = f"{kind}[{i}]"
            problems += [f"{label}: {key}.{k}: {unknown_key(k, ENTRY_KEYS)}" for k in (e.model_extra or {})]
            if e.name in seen:
                problems.append(f"{label}: {key}.name: duplicate name {e.name!r} (first used by {seen[e.name]})")
                continue
            seen[e.name] = key
            root = _entry_root(e, key, deploy_dir, env, label, problems)
            if root is None:
                continue
            mfile = manifest_file(root, e.manifest)
            if not mfile.is_file():
                what = f"{key}.manifest" if e.manifest else f"{key}.path"
                problems.append(f"{label}: {what}: package manifest not found: {mfile}")
                continue
            try:
                pm = parse_package(read_yaml(mfile), str(mfile))
            except ManifestProblems as mp:
                problems += mp.lines
                continue
            entry = ResolvedEntry(e.name, kind, i, root, mfile, pm, dict(e.config), e.autostart,
                                  e.restart_policy())
            entries.append(entry)
            if check_configs:
                from rbnx.config_check import entry_problems

                bad, notes = entry_problems(pm.configSchema, root, entry.config, f"{label}: {key} ({e.name}).config")
                problems += bad
                warnings += notes
    if problems:
        raise ManifestProblems(problems)
    atlas = model.system.atlas
    return ResolvedDeploy(path.resolve(), model.name, dict(env), atlas.listen, atlas.log, entries, warnings,
                          atlas.auth, list(atlas.allowed_hosts), atlas.restart_policy())
