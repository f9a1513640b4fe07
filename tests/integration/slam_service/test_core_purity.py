"""The SLAM core is pure: every module of ``slam_service.core`` imports, and an engine maps a few scans, in
a process where the middleware and file-format stacks (grpc, cyclonedds, mcp, yaml, pydantic, PIL) cannot
be imported at all. A fresh interpreter, so nothing this test run already imported can hide a dependency."""

from __future__ import annotations

import textwrap

from support import purity

SLAM = textwrap.dedent('''
    import importlib, math, pkgutil
    import numpy as np
    import slam_service.core as core
    modules = [m.name for m in pkgutil.iter_modules(core.__path__)]
    for name in modules:
        importlib.import_module(f"slam_service.core.{name}")
    # a 6 x 4 m box room seen from a robot stepping along x: analytic ranges, one node per step
    angles = -math.pi + 2 * math.pi / 360 * np.arange(360)
    def ranges(x, y):
        c, s = np.cos(angles), np.sin(angles)
        with np.errstate(divide="ignore"):
            tx = np.where(c > 0, (3.0 - x) / c, (-3.0 - x) / c)
            ty = np.where(s > 0, (2.0 - y) / s, (-2.0 - y) / s)
        return np.minimum(np.abs(tx), np.abs(ty)).astype(np.float32)
    eng = core.SlamEngine(core.SlamConfig())
    for k in range(4):
        pose = (-1.0 + 0.3 * k, 0.0, 0.0)
        eng.process(core.Scan(ranges(pose[0], pose[1]), -math.pi, 2 * math.pi / 360, stamp=0.1 * k), pose)
    grid = eng.map()
    assert eng.graph.n_nodes >= 3, eng.graph.n_nodes
    assert (grid.data >= 65).sum() > 100, (grid.data >= 65).sum()
    leaked = sorted(n for n in sys.modules if n.partition(".")[0] in BLOCKED)
    assert not leaked, leaked
    print("modules", len(modules), "nodes", eng.graph.n_nodes)
''')


def run_blocked(body: str) -> str:
    """Run ``body`` with the middleware and file-format stacks blocked; its stdout, or the failure's stderr."""
    proc = purity.run_blocked(body)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return proc.stdout


def test_blocker_really_blocks() -> None:
    out = run_blocked('try:\n    import yaml\nexcept ImportError as exc:\n    print("blocked", exc)\n')
    assert out.startswith("blocked")


def test_slam_core_imports_and_maps_without_middleware_or_file_formats() -> None:
    out = run_blocked(SLAM)
    assert out.startswith("modules ")
    assert int(out.split()[1]) >= 9  # engine, lookup, matcher, metrics, numeric, occupancy, posegraph, ...
