"""Example service B: resolves the odom topic through the atlas at CMD_INIT, deferring until it exists."""

from robonix_api import ATLAS, Deferred, Ok, Service

ODOM = "robonix/primitive/chassis/odom"

svc = Service("odom_consumer", "robonix/service/example")


@svc.on_init
def init(cfg: dict) -> Ok | Deferred:
    """Find a live odom provider (optionally pinned); Deferred tells rbnx boot to retry later."""
    pinned = (cfg.get("provider_ids") or {}).get("odom")
    caps = ATLAS.find_capability(contract_id=ODOM, transport="ros2", provider_id=pinned)
    if not caps:
        return Deferred(f"waiting for {ODOM}")
    with ATLAS.connect_capability(consumer_id=svc.id, provider_id=caps[0].provider_id, contract_id=ODOM,
                                  transport="ros2") as ch:
        print(f"odom from {caps[0].provider_id} on {ch.endpoint}", flush=True)
    return Ok()


if __name__ == "__main__":
    svc.run()
