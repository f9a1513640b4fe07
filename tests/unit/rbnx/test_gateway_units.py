"""Pieces of the agents-in-charge work that need no processes: `autostart`, the runner's target, the
telemetry switch, trace context over gRPC metadata, goal spans, and the control's error messages."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
import yaml

from nav2_wrapper.core import GoalRecord
from nav2_wrapper.tracing import GoalSpans
from rbnx.boot.entry import EntryRunner, Timing
from rbnx.gateway import ControlError, Entry, LifecycleControl
from rbnx.models import ManifestProblems, load_deploy
from robonix_api import telemetry

PKG = {"manifestVersion": 1, "package": {"name": "p", "version": "1", "description": "d", "license": "MIT"},
       "start": "python x.py"}


def _deploy(tmp: Path, autostart: Any) -> Path:
    (tmp / "p").mkdir()
    (tmp / "p" / "package_manifest.yaml").write_text(yaml.safe_dump(PKG))
    entry: dict[str, Any] = {"name": "svc", "path": "p"}
    if autostart is not None:
        entry["autostart"] = autostart
    path = tmp / "deploy.yaml"
    path.write_text(yaml.safe_dump({"manifestVersion": 1, "name": "d", "service": [entry], "skill": [
        {"name": "sk", "path": "p"}]}))
    return path


@pytest.mark.parametrize(("value", "autostart", "target"), [(None, True, "active"), (False, False, "inactive"),
                                                            ("false", False, "inactive"), (True, True, "active")])
def test_autostart_sets_the_boot_target(tmp_path: Path, value: Any, autostart: bool, target: str) -> None:
    d = load_deploy(_deploy(tmp_path, value))
    svc, skill = d.entries
    assert svc.autostart is autostart
    assert not d.warnings
    assert EntryRunner(svc, {}, tmp_path / "x.log", Timing()).target == target
    assert EntryRunner(skill, {}, tmp_path / "y.log", Timing()).target == "inactive"  # skills never activate


def test_autostart_must_be_a_boolean(tmp_path: Path) -> None:
    with pytest.raises(ManifestProblems) as exc:
        load_deploy(_deploy(tmp_path, "sometimes"))
    (line,) = exc.value.lines
    assert "service[0].autostart" in line
    assert "bool" in line


def test_telemetry_is_off_unless_the_standard_variables_ask() -> None:
    assert not telemetry.enabled({})
    assert telemetry.enabled({"OTEL_EXPORTER_OTLP_ENDPOINT": "http://127.0.0.1:4318"})
    assert telemetry.enabled({"OTEL_EXPORTER_OTLP_TRACES_ENDPOINT": "http://127.0.0.1:4318/v1/traces"})
    assert not telemetry.enabled({"OTEL_EXPORTER_OTLP_ENDPOINT": "http://x", "OTEL_SDK_DISABLED": "true"})
    assert not telemetry.enabled({"OTEL_EXPORTER_OTLP_ENDPOINT": "http://x", "OTEL_TRACES_EXPORTER": "none"})
    # off in this process: no tracer, no propagation work, no spans to build
    assert telemetry.tracer() is None
    assert telemetry.grpc_metadata() == []
    assert GoalSpans.maybe("map") is None


class _Ctx:
    def __init__(self, md: list[tuple[str, str]]) -> None:
        self.md = md

    def invocation_metadata(self) -> list[tuple[str, str]]:
        return self.md


def test_goal_span_continues_the_callers_trace(monkeypatch: pytest.MonkeyPatch) -> None:
    from opentelemetry.sdk.trace import TracerProvider
    from opentelemetry.sdk.trace.export import SimpleSpanProcessor
    from opentelemetry.sdk.trace.export.in_memory_span_exporter import InMemorySpanExporter

    exporter = InMemorySpanExporter()
    provider = TracerProvider()
    provider.add_span_processor(SimpleSpanProcessor(exporter))
    monkeypatch.setattr(telemetry, "_tracer", provider.get_tracer("test"))
    tid, sid = "0af7651916cd43dd8448eb211c80319c", "b7ad6b7169203331"
    parent = telemetry.context_from_grpc(_Ctx([("traceparent", f"00-{tid}-{sid}-01"), ("x-bin", "v")]))
    spans = GoalSpans.maybe("map")
    assert spans is not None
    rec = GoalRecord("nav-1", (3.0, 4.0, 0.0), state="RUNNING", started=1.0)
    spans.start(rec, parent, (0.0, 0.0, 0.0))
    spans.sweep((1.0, 0.0, 0.0))
    spans.sweep((3.0, 4.0, 0.0))
    assert not exporter.get_finished_spans()  # still running: the span stays open
    rec.state, rec.finished, rec.recoveries = "SUCCEEDED", 9.0, 1
    spans.sweep((3.0, 4.0, 0.0))
    (span,) = exporter.get_finished_spans()
    assert span.name == "nav.navigate"
    assert format(span.context.trace_id, "032x") == tid
    assert format(span.parent.span_id, "016x") == sid
    a = span.attributes
    assert a["nav.goal_distance_m"] == pytest.approx(5.0)
    assert a["nav.end_state"] == "SUCCEEDED"
    assert a["nav.distance_driven_m"] == pytest.approx(1.0 + 20 ** 0.5, abs=1e-3)
    assert a["nav.final_error_m"] == 0.0
    assert a["nav.recoveries"] == 1
    assert a["nav.duration_s"] == 8.0


def test_control_names_unknown_entries_and_bad_patches() -> None:
    c = LifecycleControl("127.0.0.1:1", [Entry("mapping", "service", {"mode": "mapping"}),
                                         Entry("nav2", "service", {})])
    with pytest.raises(ControlError, match=r"unknown entry 'slam'; known: mapping, nav2"):
        c.activate("slam")
    with pytest.raises(ControlError, match=r"entry: required, one of mapping, nav2"):
        c.deactivate("")
    with pytest.raises(ControlError, match=r"config: must be a JSON object .*got list"):
        c.configure("mapping", [1])
    with pytest.raises(ControlError, match=r"name an entry"):
        c.shutdown()
