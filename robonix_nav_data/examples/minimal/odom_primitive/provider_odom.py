"""Example primitive A: offers the chassis odom topic once configured (CMD_INIT)."""

from robonix_api import Ok, Primitive

ODOM = "robonix/primitive/chassis/odom"

prim = Primitive("odom_primitive", "robonix/primitive/chassis")


@prim.on_init
def init(cfg: dict) -> Ok:
    """Declare the topic at INIT so consumers only see it once this primitive is configured."""
    topic = prim.declare_ros2_topic(ODOM, str(cfg.get("topic", "/odom")), qos="reliable")
    print(f"odom offered on {topic}", flush=True)
    return Ok()


if __name__ == "__main__":
    prim.run()
