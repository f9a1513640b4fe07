"""Where the project's shipped files are: one place, through ``importlib.resources``.

Why: code used to walk up from its own file to the repository root (``Path(__file__).parents[2] /
"config"``), which only works in a source checkout; an installed wheel has no repository root. The
files now ship as package data (this package for the root's config/, examples/, scripts/ and the
navigation package's manifests; ``atlas`` for the contract catalogue; ``hal_panda_mobile`` for scenes),
so the same lookups work in an editable checkout and in site-packages. Importing this module is cheap
and pulls in no third-party code, so algorithm cores may use it too.
"""

from __future__ import annotations

import re
import shutil
from importlib import resources
from pathlib import Path

DATA_PACKAGE = "robonix_nav_data"
EXAMPLES = ("sim", "real_robot", "minimal")


class ResourceError(FileNotFoundError):
    """A shipped file is missing: the install is incomplete (the message says which file)."""


def _package_dir(package: str) -> Path:
    """The on-disk folder of an installed package (wheels are unpacked, so it is a real folder)."""
    return Path(str(resources.files(package)))


def data_root() -> Path:
    """The installed form of the repository root: config/, examples/, scripts/, package_manifest*.yaml."""
    return _package_dir(DATA_PACKAGE)


def _existing(path: Path, what: str) -> Path:
    """``path`` with symlinks resolved (a checkout reaches the root's folders through links), or an error."""
    path = path.resolve()
    if not path.exists():
        raise ResourceError(f"{what} not found at {path}: the robonix-nav install is incomplete "
                            "(reinstall it; a source checkout needs `pip install -e .` again)")
    return path


def config_dir() -> Path:
    return _existing(data_root() / "config", "config directory")


def config_file(name: str) -> Path:
    """A file of config/ (robot description, Nav2 params profiles, DDS config)."""
    return _existing(data_root() / "config" / name, f"config file {name!r}")


def robot_description() -> Path:
    """The panda_mobile robot description, the one source for simulator, costmap and map card."""
    return config_file("panda_mobile.yaml")


def contracts_root() -> Path:
    """The contract catalogue (robonix TOML files) shipped with the atlas package."""
    return _package_dir("atlas") / "contracts"


def scenes_dir() -> Path:
    """The built-in simulator scenes."""
    return _package_dir("hal_panda_mobile") / "scenes"


def examples_dir() -> Path:
    return _existing(data_root() / "examples", "examples directory")


def example_deploy(name: str = "sim") -> Path:
    """The shipped deploy file of an example (``sim``, ``real_robot``, ``minimal``)."""
    return _existing(examples_dir() / name / "deploy.yaml", f"example deploy {name!r}")


def resolve_data_path(path: str | Path) -> Path:
    """A user-given relative path: the working directory first, then the shipped data root.

    Lets configs say ``config/panda_mobile.yaml`` whether they run from a checkout or an install.
    """
    p = Path(path).expanduser()
    if p.is_absolute() or p.exists():
        return p
    return data_root() / p


_PATH_LINE = re.compile(r"^(?P<lead>\s*(?:-\s+)?path:\s*)(?P<value>[^\s#]+)(?P<rest>.*)$")


#: Set by rbnx (rbnx.models) to :func:`data_root` unless the environment has it: deploy files written by
#: ``rbnx init`` name the installed packages through it.
DATA_ROOT_ENV = "RBNX_DATA_ROOT"


def _portable(target: Path) -> str:
    """``${RBNX_DATA_ROOT}/<relative>`` for a folder of this installation, else the absolute path."""
    root = data_root().resolve()
    try:
        rel = target.resolve().relative_to(root)
    except ValueError:
        return str(target)
    return f"${{{DATA_ROOT_ENV}}}/{rel.as_posix()}" if rel.parts else f"${{{DATA_ROOT_ENV}}}"


def copy_examples(dest: Path, names: tuple[str, ...] = EXAMPLES) -> list[Path]:
    """Write the example deploy folders under ``dest`` for a user to edit; returns the deploy files.

    An entry's ``path:`` that pointed into the installed tree (``../../hal_panda_mobile``) would not
    resolve from ``dest``, so it is rewritten to ``${RBNX_DATA_ROOT}/hal_panda_mobile``: rbnx sets
    ``RBNX_DATA_ROOT`` to wherever this robonix-nav is installed, so the copy keeps working after a
    reinstall, in another venv or on another machine (no absolute site-packages path is written). Paths
    inside the example itself (the minimal example's own packages) stay relative. Comments and layout are
    kept; comments naming ``examples/<name>/deploy.yaml`` name the copy instead. Refuses to overwrite: an
    existing ``dest/<name>`` is an error.
    """
    src_root = examples_dir()
    clashes = [dest / n for n in names if (dest / n).exists()]
    if clashes:
        raise FileExistsError(f"{clashes[0]} already exists; choose another directory or remove it")
    written = []
    for name in names:
        src, out = src_root / name, dest / name
        shutil.copytree(src, out, symlinks=False, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
        deploy = out / "deploy.yaml"
        lines = []
        for line in deploy.read_text(encoding="utf-8").splitlines(keepends=True):
            m = _PATH_LINE.match(line.rstrip("\n"))
            if m and not Path(m["value"]).is_absolute() and "$" not in m["value"]:
                target = (src / m["value"]).resolve()
                inside = target == src.resolve() or src.resolve() in target.parents
                if target.is_dir() and not inside:
                    line = f"{m['lead']}{_portable(target)}{m['rest']}\n"
            elif line.lstrip().startswith("#"):
                line = line.replace(f"examples/{name}/deploy.yaml", f"{name}/deploy.yaml")
            lines.append(line)
        deploy.write_text("".join(lines), encoding="utf-8")
        written.append(deploy)
    return written
