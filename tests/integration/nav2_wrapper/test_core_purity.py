"""The navigation core imports and plans where gRPC, DDS, MCP, YAML and pydantic cannot be imported."""

from __future__ import annotations

from support import purity

BLOCKED = (*purity.MIDDLEWARE_AND_FORMATS, "robonix_api", "robonix_nav_data")

PROBE = """
import importlib, pkgutil
import nav2_wrapper.core as core
mods = sorted(m.name for m in pkgutil.iter_modules(core.__path__, "nav2_wrapper.core."))
for name in mods:
    importlib.import_module(name)
import numpy as np
from robonix_common.grid import GridMap
fp = core.Footprint(np.array([[0.35, 0.25], [-0.35, 0.25], [-0.35, -0.25], [0.35, -0.25]]))
grid = np.zeros((60, 60), np.int8)
grid[0:45, 28:32] = 100
cm = core.Costmap(core.CostmapConfig(obstacle_layer=False, footprint=fp))
cm.set_static_map(GridMap(grid, 0.05))
res = core.GlobalPlanner(core.PlannerConfig()).plan(cm, (0.5, 0.5), (2.5, 0.5))
assert res.ok, res.reason
assert res.length > 2.0, res.length
nav = core.Navigator(core.NavConfig.defaults(fp))
leaked = sorted(m for m in sys.modules if m.split(".")[0] in BLOCKED)
print("OK", len(mods), round(res.length, 2), leaked)
"""


def test_core_imports_and_plans_without_middleware_or_file_formats() -> None:
    out = purity.run_blocked(PROBE, BLOCKED)
    assert out.returncode == 0, out.stderr[-3000:]
    words = out.stdout.split()
    assert words[0] == "OK", out.stdout
    assert int(words[1]) >= 10, out.stdout          # every module of the core was imported
    assert float(words[2]) > 2.0, out.stdout        # the path goes around the wall
    assert out.stdout.rstrip().endswith("[]"), out.stdout


def test_blocker_really_blocks() -> None:
    """The probe's finder makes a blocked package unimportable (so a pass above means something)."""
    out = purity.run_blocked("import yaml\n", BLOCKED, timeout=60)
    assert out.returncode != 0
    assert "yaml is blocked" in out.stderr
