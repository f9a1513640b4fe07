"""Pure units: env expansion, backoff, progress rendering, state file, driver path (the process helpers
run real processes: tests/integration/rbnx/test_rbnx_process_groups.py)."""

from __future__ import annotations

import io
from pathlib import Path

import pytest

from rbnx.boot.backoff import Backoff
from rbnx.boot.progress import ProgressView, Row, plain_line, render_table
from rbnx.boot.statefile import read_state, state_path, write_state
from rbnx.envexpand import UndefinedVariable, apply_env_section, expand_str, expand_tree


def test_expand_forms() -> None:
    env = {"A": "1", "B_2": "two"}
    assert expand_str("$A-${B_2}-${C:-dflt}-$$A-${A:-x}", env) == "1-two-dflt-$A-1"
    assert expand_str("no vars", env) == "no vars"
    with pytest.raises(UndefinedVariable):
        expand_str("$MISSING", env)


def test_expand_tree_reports_paths() -> None:
    problems: list[str] = []
    out = expand_tree({"a": ["$X", {"b": "${Y}"}], "n": 3}, {"X": "x"}, "", problems)
    assert out == {"a": ["x", {"b": "${Y}"}], "n": 3}
    assert problems == ["a[1].b: undefined variable $Y"]


def test_env_section_in_order() -> None:
    problems: list[str] = []
    env = apply_env_section({"A": "/opt", "B": "$A/bin", "C": 5, "D": True, "E": None, "F": [1]}, {}, problems)
    assert (env["B"], env["C"], env["D"], env["E"]) == ("/opt/bin", "5", "true", "")
    assert problems == ["env.F: must be a string or number, not list"]


def test_backoff_doubles_and_caps() -> None:
    b = Backoff(0.2, 2.0, 2.0)
    assert [round(b.next_delay(), 3) for _ in range(6)] == [0.2, 0.4, 0.8, 1.6, 2.0, 2.0]
    b.reset()
    assert b.next_delay() == 0.2


def test_render_table_columns_and_truncation() -> None:
    rows = [Row("odom_consumer", "service", "deferred", "waiting for robonix/primitive/chassis/odom", 10.0),
            Row("a", "primitive", "active", "", 10.0, 11.5), Row("b", "skill")]
    lines = render_table(rows, now=12.0, width=60)
    assert lines[0].split() == ["NAME", "KIND", "STATE", "TIME"]
    assert lines[1].startswith("odom_consumer  service")
    assert lines[1].endswith("2.0s")
    assert "…" in lines[1]
    assert all(len(line) <= 60 for line in lines)
    assert lines[2].split() == ["a", "primitive", "active", "1.5s"]
    assert lines[3].split() == ["b", "skill", "pending", "-"]


def test_plain_progress_prints_each_change_once() -> None:
    buf = io.StringIO()
    view = ProgressView([Row("a", "service")], stream=buf, tty=False, t0=0.0)
    view.set("a", "starting")
    view.set("a", "starting")
    view.set("a", "deferred", "waiting for x")
    lines = buf.getvalue().splitlines()
    assert len(lines) == 2
    assert lines[1].endswith("a (service): deferred(waiting for x)")
    assert plain_line(Row("a", "k", "active"), 3.0, 1.0) == "[   2.0s] a (k): active"


def test_tty_progress_redraws_in_place() -> None:
    buf = io.StringIO()
    view = ProgressView([Row("a", "service"), Row("b", "primitive")], stream=buf, tty=True)
    view.set("a", "starting")
    view.set("a", "active")
    out = buf.getvalue()
    assert out.count("\x1b[3F") == 1  # second draw moves up over the 3-line table
    assert "active" in out.splitlines()[-2]


def test_disabled_progress_is_silent() -> None:
    buf = io.StringIO()
    view = ProgressView([Row("a", "service")], stream=buf, enabled=False)
    view.set("a", "failed", "x")
    assert buf.getvalue() == ""
    assert view.row("a").label() == "failed(x)"


def test_state_file_roundtrip(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("RBNX_STATE_DIR", str(tmp_path))
    p = state_path(tmp_path / "deploy.yaml")
    assert p.parent == tmp_path
    assert p.name.startswith("boot-deploy-")
    write_state(p, {"pid": 1}, copy_to=tmp_path / "copy.json")
    assert read_state(p) == {"pid": 1} == read_state(tmp_path / "copy.json")
    assert read_state(tmp_path / "none.json") is None


def test_driver_path_follows_the_declared_service() -> None:
    """rbnx drives whatever Driver a provider declared: ours, robonix-api's per-namespace one, or Rust's."""
    from rbnx.atlas_rpc import DEFAULT_DRIVER_PATH, driver_method_path
    from robonix_api.proto_gen import atlas_pb2

    def grpc_params(service: str, method: str) -> atlas_pb2.TransportParams:
        return atlas_pb2.TransportParams(grpc=atlas_pb2.GrpcParams(proto_file="robonix_contracts.proto",
                                                                   service_name=service, method=method))

    assert driver_method_path(None) == DEFAULT_DRIVER_PATH
    assert driver_method_path(atlas_pb2.TransportParams()) == DEFAULT_DRIVER_PATH
    assert driver_method_path(grpc_params("RobonixPrimitiveLidarDriver", "Driver")) == \
        "/robonix.contracts.RobonixPrimitiveLidarDriver/Driver"
    assert driver_method_path(grpc_params("robonix.contracts.RobonixLifecycleDriver",
                                          "/robonix.contracts.RobonixLifecycleDriver/Driver")) == DEFAULT_DRIVER_PATH
