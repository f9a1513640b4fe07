"""OpenTelemetry tracing for providers and rbnx, switched on only by the standard ``OTEL_*`` variables.

Off by default and free when off: nothing of the OpenTelemetry SDK is imported, :func:`tracer` returns
``None`` and callers skip building span attributes (a map PNG is only rendered when someone listens).
On when ``OTEL_EXPORTER_OTLP_ENDPOINT`` or ``OTEL_EXPORTER_OTLP_TRACES_ENDPOINT`` is set, unless
``OTEL_SDK_DISABLED=true`` or ``OTEL_TRACES_EXPORTER=none``. Spans then go to an OTLP/HTTP (protobuf)
exporter, which reads the rest of the standard variables itself (headers, timeout, compression,
``OTEL_BSP_*`` batching); ``OTEL_SERVICE_NAME`` / ``OTEL_RESOURCE_ATTRIBUTES`` name the process.

Trace context crosses gRPC as W3C ``traceparent``/``tracestate`` metadata (:func:`context_from_grpc`,
:func:`grpc_metadata`), so an agent's trace continues into a Navigate goal or a lifecycle command.
"""

from __future__ import annotations

import logging
import os
import sys
import threading
from collections.abc import Iterable, Mapping
from typing import Any

log = logging.getLogger(__name__)

ENDPOINT_VARS = ("OTEL_EXPORTER_OTLP_TRACES_ENDPOINT", "OTEL_EXPORTER_OTLP_ENDPOINT")
INSTRUMENTATION = "robonix-nav"

_lock = threading.Lock()
_tracer: Any = None
_provider: Any = None
_configured = False


def enabled(env: Mapping[str, str] | None = None) -> bool:
    """Whether the standard variables ask for traces (an endpoint set, the SDK not disabled)."""
    env = os.environ if env is None else env
    if env.get("OTEL_SDK_DISABLED", "").strip().lower() == "true":
        return False
    exporters = {e.strip().lower() for e in env.get("OTEL_TRACES_EXPORTER", "otlp").split(",")}
    if exporters <= {"none", ""}:
        return False
    return any(env.get(v, "").strip() for v in ENDPOINT_VARS)


def setup(service_name: str) -> Any:
    """Install the tracer provider once per process (when :func:`enabled`); returns :func:`tracer`.

    ``service_name`` is used unless ``OTEL_SERVICE_NAME`` names the process already. Spans are batched
    and flushed at exit (the SDK's atexit hook) and by :func:`shutdown`.
    """
    global _tracer, _provider, _configured
    with _lock:
        if _configured:
            return _tracer
        _configured = True
        if not enabled():
            return None
        try:
            from opentelemetry import trace
            from opentelemetry.exporter.otlp.proto.http.trace_exporter import OTLPSpanExporter
            from opentelemetry.sdk.resources import SERVICE_NAME, Resource
            from opentelemetry.sdk.trace import TracerProvider
            from opentelemetry.sdk.trace.export import BatchSpanProcessor
        except ImportError as exc:  # an install without the telemetry packages: say so once, run untraced
            log.warning("OTEL endpoint set but OpenTelemetry SDK unavailable (%s); tracing off", exc)
            return None
        attrs = {} if os.environ.get("OTEL_SERVICE_NAME") else {SERVICE_NAME: service_name}
        provider = TracerProvider(resource=Resource.create(attrs))
        provider.add_span_processor(BatchSpanProcessor(OTLPSpanExporter()))
        trace.set_tracer_provider(provider)
        _provider = provider
        _tracer = provider.get_tracer(INSTRUMENTATION)
        endpoint = next((os.environ[v] for v in ENDPOINT_VARS if os.environ.get(v, "").strip()), "")
        log.info("tracing on: service %s, OTLP/HTTP to %s", service_name, endpoint)
        return _tracer


def tracer() -> Any:
    """The process tracer, or ``None`` when tracing is off (callers then do no tracing work at all)."""
    return _tracer


def shutdown(timeout_s: float = 5.0) -> None:
    """Flush pending spans (before a process exits on its own terms)."""
    if _provider is not None:
        try:
            _provider.force_flush(int(timeout_s * 1000))
        except Exception as exc:  # a collector that is away must not fail the shutdown
            log.debug("span flush failed: %s", exc)


def context_from_grpc(grpc_context: Any) -> Any:
    """The caller's trace context from a gRPC servicer context's metadata (``None`` when off/absent)."""
    if _tracer is None or grpc_context is None:
        return None
    try:
        md = grpc_context.invocation_metadata() or ()
    except Exception:  # not a real servicer context (e.g. the MCP face calls handlers without one)
        return None
    return context_from_carrier({k: v for k, v in md if isinstance(v, str)})


def context_from_carrier(carrier: Mapping[str, str]) -> Any:
    """W3C trace context from a mapping of headers (``traceparent`` / ``tracestate``)."""
    if _tracer is None or "traceparent" not in carrier:
        return None
    from opentelemetry.trace.propagation.tracecontext import TraceContextTextMapPropagator

    return TraceContextTextMapPropagator().extract(carrier=dict(carrier))


def grpc_metadata() -> list[tuple[str, str]]:
    """``traceparent``/``tracestate`` of the current span as gRPC metadata.

    Also when this process does not trace but someone else's context is current (the gateway relays an
    agent's MCP call, whose ``_meta`` the MCP SDK made current): the trace then continues in the provider.
    Empty, and no OpenTelemetry import, in a process that neither traces nor has loaded OpenTelemetry.
    """
    if _tracer is None and "opentelemetry.trace" not in sys.modules:
        return []
    from opentelemetry.trace import get_current_span
    from opentelemetry.trace.propagation.tracecontext import TraceContextTextMapPropagator

    if not get_current_span().get_span_context().is_valid:
        return []
    carrier: dict[str, str] = {}
    TraceContextTextMapPropagator().inject(carrier)
    return list(carrier.items())


def set_attributes(span: Any, attrs: Iterable[tuple[str, Any]]) -> None:
    """Set the attributes whose value is not ``None`` (OpenTelemetry rejects None)."""
    for k, v in attrs:
        if v is not None:
            span.set_attribute(k, v)


__all__ = ["context_from_carrier", "context_from_grpc", "enabled", "grpc_metadata", "set_attributes", "setup",
           "shutdown", "tracer"]
