"""Only the deployment's writers may command the base (issue 37 item 4: a process of user ``nobody``
publishing /cmd_vel moved the robot 0.88 m). Three real DDS participants in this process: one created with
the deployment token (a provider under ``rbnx boot``), one without (any other local user), one with another
deployment's token; a reader with ``WriterTrust`` accepts the first one's samples only."""

from __future__ import annotations

import threading

import pytest
from support.wait import wait_until

from robonix_api import auth
from robonix_api.dds import DdsNode, Twist
from robonix_api.dds.convert import twist
from robonix_api.dds.writer_trust import WriterTrust, deployment_tag

pytestmark = pytest.mark.integration
TOPIC = "/cmd_vel_trust_test"


def _node(monkeypatch: pytest.MonkeyPatch, token: str, name: str) -> DdsNode:
    if token:
        monkeypatch.setenv(auth.TOKEN_ENV, token)
    else:
        monkeypatch.delenv(auth.TOKEN_ENV, raising=False)
    return DdsNode(name=name)


def test_only_writers_of_the_deployment_are_accepted(monkeypatch: pytest.MonkeyPatch) -> None:
    ours = _node(monkeypatch, "deploy-token-A", "ours")
    stranger = _node(monkeypatch, "", "stranger")
    other = _node(monkeypatch, "deploy-token-B", "other-deployment")
    hal = _node(monkeypatch, "deploy-token-A", "hal")
    seen: dict[float, list[bool]] = {1.0: [], 2.0: [], 3.0: []}
    lock = threading.Lock()
    trust = WriterTrust(hal.participant, deployment_tag("deploy-token-A"))

    def on_twist(msg: Twist) -> None:
        ok = trust.allowed(msg.sample_info.publication_handle)
        with lock:
            seen[round(float(msg.linear.x), 1)].append(ok)

    try:
        hal.create_subscription(TOPIC, Twist, on_twist, "reliable")
        pubs = {1.0: ours.create_publisher(TOPIC, Twist, "reliable"),
                2.0: stranger.create_publisher(TOPIC, Twist, "reliable"),
                3.0: other.create_publisher(TOPIC, Twist, "reliable")}

        def settled() -> bool:
            for vx, pub in pubs.items():
                pub.publish(twist(vx, 0.0, 0.0))
            with lock:  # a writer's first samples may arrive before discovery names it: refused, then decided
                return all(len(v) >= 3 for v in seen.values()) and any(seen[1.0])

        wait_until(settled, 30, "samples from all three writers", 0.1)
        with lock:
            assert seen[1.0][-1] is True
            assert not any(seen[2.0]), "a writer without the deployment's token was accepted"
            assert not any(seen[3.0]), "another deployment's writer was accepted"
    finally:
        for n in (ours, stranger, other, hal):
            n.close()
