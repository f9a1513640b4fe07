"""The committed proto and stubs must be exactly what the codegen produces from the sources."""

import filecmp
from pathlib import Path

from robonix_api import codegen
from robonix_api.contracts import builtin_contract, contract_service_name, load_catalogue, upper_camel


def test_contracts_proto_is_fresh():
    rendered = codegen.render_contracts_proto(load_catalogue([codegen.BUILTIN_ROOT]))
    committed = (codegen.PROTO_DIR / codegen.CONTRACTS_PROTO).read_text()
    assert rendered == committed, "proto/robonix_contracts.proto is stale: run python -m robonix_api.codegen"


def test_generated_stubs_are_fresh(tmp_path: Path):
    codegen.generate(codegen.PROTO_DIR, tmp_path)
    names = sorted(p.name for p in tmp_path.iterdir() if p.is_file())
    committed = sorted(p.name for p in codegen.OUT_DIR.iterdir() if p.is_file())
    assert names == committed
    _, mismatch, errors = filecmp.cmpfiles(tmp_path, codegen.OUT_DIR, names, shallow=False)
    assert not mismatch, f"stale stubs {mismatch}: run python -m robonix_api.codegen"
    assert not errors, f"stale stubs {mismatch}: run python -m robonix_api.codegen"


def test_naming_rules_match_robonix():
    assert contract_service_name("robonix/service/navigation/navigate/status") == (
        "RobonixServiceNavigationNavigateStatus"
    )
    assert upper_camel("scan_2d") == "Scan2d"
    assert builtin_contract("robonix/lifecycle/driver").grpc_path == (
        "/robonix.contracts.RobonixLifecycleDriver/Driver"
    )
    assert builtin_contract("robonix/primitive/chassis/twist_in").method_name == "TwistIn"
    assert builtin_contract("robonix/service/map/occupancy_grid").method_name == "OccupancyGrid"
    assert builtin_contract("robonix/service/navigation/navigate/status").method_name == "GetNavigationStatus"
