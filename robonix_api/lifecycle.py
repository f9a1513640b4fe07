"""robonix-api's ``robonix_api.lifecycle``: Driver command codes and the contract -> servicer helpers.

The Driver's state machine itself is :class:`robonix_api.driver.Lifecycle` (stricter than robonix-api's:
illegal transitions are refused, see COMPAT.md); ``build_lifecycle_servicer`` puts robonix-api's
signature on it for code that assembles its own gRPC server.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import Any

from robonix_api.driver import CMD_ACTIVATE, CMD_DEACTIVATE, CMD_INIT, CMD_SHUTDOWN, Lifecycle, pascal

contract_id_to_pascal = pascal  # ``robonix/primitive/chassis/twist_in`` -> ``RobonixPrimitiveChassisTwistIn``


def driver_pascal_for_namespace(namespace: str) -> str:
    """``robonix/primitive/lidar`` -> ``RobonixPrimitiveLidarDriver`` (the namespace driver's service)."""
    return pascal(f"{namespace.strip('/')}/driver")


def resolve_servicer(contract_id: str, contracts_grpc_module: Any) -> tuple[type, str, Callable[..., Any], str] | None:
    """``(servicer class, method name, add-to-server function, service name)`` generated for a contract
    in ``contracts_grpc_module``, or None when it has none."""
    base = pascal(contract_id)
    cls = getattr(contracts_grpc_module, f"{base}Servicer", None)
    add = getattr(contracts_grpc_module, f"add_{base}Servicer_to_server", None)
    if cls is None or add is None:
        return None
    methods = [n for n, v in vars(cls).items() if not n.startswith("_") and callable(v)]
    return (cls, methods[0], add, base) if methods else None


def bind_user_handler(servicer_cls: type, method_name: str, fn: Callable[..., Any]) -> type:
    """A subclass of ``servicer_cls`` whose ``method_name`` calls ``fn(request)`` or
    ``fn(request, context)`` (by the number of parameters ``fn`` takes)."""
    from robonix_api.grpc_contracts import invoke

    def method(self: Any, request: Any, context: Any) -> Any:
        return invoke(fn, request, context)

    return type(f"{servicer_cls.__name__}Impl", (servicer_cls,), {method_name: method})


def parse_cfg(request: Any) -> dict[str, Any]:
    """A Driver request's ``config_json``: empty or non-object -> {}; invalid JSON -> ValueError."""
    text = (getattr(request, "config_json", "") or "").strip()
    if not text:
        return {}
    from robonix_api.driver import CONFIG_JSON_MAX_BYTES, CONFIG_JSON_MAX_DEPTH, json_depth

    if len(text) > CONFIG_JSON_MAX_BYTES or json_depth(text) > CONFIG_JSON_MAX_DEPTH:
        raise ValueError(f"bad config_json: larger than {CONFIG_JSON_MAX_BYTES} bytes or nested deeper than "
                         f"{CONFIG_JSON_MAX_DEPTH} levels")
    try:
        value = json.loads(text)
    except (json.JSONDecodeError, RecursionError) as exc:
        raise ValueError(f"bad config_json: {str(exc)[:200]}") from None
    return value if isinstance(value, dict) else {}


def coerce_response(response_cls: Any, ret: Any) -> Any:
    """None -> ok/"ready"; a dict ``{ok, state, error}`` -> ``response_cls``; anything else as it is."""
    if ret is None:
        return response_cls(ok=True, state="ready", error="")
    if isinstance(ret, dict):
        return response_cls(ok=bool(ret.get("ok", True)), state=str(ret.get("state", "ready")),
                            error=str(ret.get("error", "")))
    return ret


def build_lifecycle_servicer(namespace: str, contracts_grpc_module: Any, response_cls: Any, *,
                             on_init: Callable[..., Any] | None = None,
                             on_activate: Callable[..., Any] | None = None,
                             on_deactivate: Callable[..., Any] | None = None,
                             on_shutdown: Callable[..., Any] | None = None,
                             on_state_change: Callable[[str | None, str], None] | None = None,
                             log_tag: str = "robonix_api") -> tuple[Any, Callable[..., Any], str, str] | None:
    """``(servicer, add-to-server function, service name, "Driver")`` for the namespace's generated
    ``<namespace>/driver`` servicer, or None when ``contracts_grpc_module`` has none.

    ``on_state_change(state, detail)`` gets ``"inactive"``/``"active"``/``"error"``/``"terminated"``,
    or ``None`` with the reason when a handler answers Deferred (state unchanged)."""
    base = driver_pascal_for_namespace(namespace)
    cls = getattr(contracts_grpc_module, f"{base}Servicer", None)
    add = getattr(contracts_grpc_module, f"add_{base}Servicer_to_server", None)
    if cls is None or add is None:
        return None
    lifecycle = Lifecycle()
    lifecycle.handlers.update(init=on_init, activate=on_activate, deactivate=on_deactivate, shutdown=on_shutdown)
    if on_state_change is not None:
        last = {"state": lifecycle.state}

        def push(state: str, detail: str) -> None:
            changed = state != last["state"]
            last["state"] = state
            on_state_change(state if changed else None, detail)

        lifecycle.set_push(push)

    def driver(self: Any, request: Any, context: Any) -> Any:
        try:
            reply = lifecycle.handle(request.command, request.config_json)
        except ValueError as exc:  # malformed config_json: fail the RPC as robonix-api does
            import grpc

            context.abort(grpc.StatusCode.INVALID_ARGUMENT, str(exc))
        return response_cls(ok=reply.ok, state=reply.state, error=reply.error)

    servicer = type(f"{log_tag}LifecycleServicer".replace("/", "_"), (cls,), {"Driver": driver})()
    servicer.lifecycle = lifecycle
    return servicer, add, base, "Driver"



__all__ = ["CMD_ACTIVATE", "CMD_DEACTIVATE", "CMD_INIT", "CMD_SHUTDOWN", "bind_user_handler",
           "build_lifecycle_servicer", "coerce_response", "contract_id_to_pascal", "driver_pascal_for_namespace",
           "parse_cfg", "resolve_servicer"]
