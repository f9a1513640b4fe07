"""The simulator core is pure: every module of ``hal_panda_mobile.sim`` imports, and a sim built from plain
dataclasses steps and scans, in a process where grpc, cyclonedds, mcp, yaml, pydantic and PIL cannot be
imported (robot and scene files are :mod:`hal_panda_mobile.files`' job). Its modules form no import cycle."""

from __future__ import annotations

import ast
import textwrap
from pathlib import Path

from support import purity

import hal_panda_mobile.sim

SIM = textwrap.dedent('''
    import importlib, math, pkgutil
    import numpy as np
    import hal_panda_mobile.sim as sim
    modules = [m.name for m in pkgutil.iter_modules(sim.__path__)]
    for name in modules:
        importlib.import_module(f"hal_panda_mobile.sim.{name}")
    robot = sim.RobotDescription(footprint=((0.35, 0.25), (-0.35, 0.25), (-0.35, -0.25), (0.35, -0.25)),
                                 limits=sim.LimitsSpec(0.5, 0.5, 1.5, 1.0, 1.0, 2.0))
    walls = tuple(sim.Wall(start=a, end=b) for a, b in (((-3, -2), (3, -2)), ((3, -2), (3, 2)), ((3, 2), (-3, 2)),
                                                         ((-3, 2), (-3, -2))))
    scene = sim.Scene(name="box_room", bounds=(-3.0, -2.0, 3.0, 2.0), start=(0.0, 0.0, 0.0), walls=walls)
    s = sim.PandaMobileSim(robot, scene, seed=1, odom_noise=sim.OdomNoise.realistic())
    s.set_cmd_vel(0.4, 0.0, 0.0)
    s.step(100)
    x = s.ground_truth()[0]
    scan = s.scan()
    assert 0.0 < x < 0.2, x
    hits = np.isfinite(scan.ranges).sum()
    assert hits == len(scan.ranges) and abs(float(scan.ranges[len(scan.ranges) // 2]) - (3.0 - 0.05 - x)) < 0.02
    leaked = sorted(n for n in sys.modules if n.partition(".")[0] in BLOCKED)
    assert not leaked, leaked
    print("modules", len(modules), "x", round(x, 3))
''')


def test_sim_imports_and_steps_without_middleware_or_file_formats() -> None:
    proc = purity.run_blocked(SIM)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert int(proc.stdout.split()[1]) >= 10  # engine, errors, lidar, mjcf, odometry, raster, robot, scene, ...


def _local_imports(path: Path) -> set[str]:
    """Sibling modules a module imports (``from .x import``, at any depth: lazy imports count too)."""
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.level == 1 and node.module:
            out.add(node.module.partition(".")[0])
    return out


def test_sim_modules_form_no_import_cycle() -> None:
    root = Path(hal_panda_mobile.sim.__file__).parent
    graph = {p.stem: _local_imports(p) for p in root.glob("*.py") if p.stem != "__init__"}
    state: dict[str, int] = {}  # 1 visiting, 2 done

    def visit(node: str, trail: list[str]) -> None:
        if state.get(node) == 2:
            return
        assert state.get(node) != 1, "import cycle: " + " -> ".join([*trail, node])
        state[node] = 1
        for dep in sorted(graph.get(node, ())):
            visit(dep, [*trail, node])
        state[node] = 2

    for module in sorted(graph):
        visit(module, [])
    assert graph["raster"] == {"scene", "shapes"}  # the old raster -> scene -> worldgen -> raster loop is gone
