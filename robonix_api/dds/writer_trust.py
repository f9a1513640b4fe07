"""Who may write to a topic: the deployment's own DDS participants, told apart through DDS discovery.

Why (issue 37 item 4): any local user could publish ``/cmd_vel`` on the deployment's domain and drive the
robot (0.88 m by a process of user ``nobody``). The Cyclone DDS wheel ships no DDS Security plugins, so
authenticated DDS is not available here; what is: every participant announces its USER_DATA QoS in
discovery (builtin topic DCPSParticipant), every writer its participant (DCPSPublication), and every
received sample names its writer (``sample_info.publication_handle``).

A participant of a provider started with the deployment token (``ROBONIX_DEPLOY_TOKEN``) carries
``rbnx_deploy=<tag>;`` in its USER_DATA (beside rmw's ``enclave=/;``, key=value pairs as rmw
writes them), the tag a one-way hash of the token: it names the deployment
without revealing the token. A reader that trusts only the deployment checks each sample's writer: its
participant must carry the same tag. This stops other local users and foreign robots on the domain that
do not know the token; it is not cryptographic authentication (a hostile process that reads the tag off
the network can copy it) — for that, use DDS Security (see docs/trust-dds.md).
"""

from __future__ import annotations

import hashlib
import logging
import threading
import time
from typing import Any

from cyclonedds.builtin import BuiltinDataReader, BuiltinTopicDcpsParticipant, BuiltinTopicDcpsPublication
from cyclonedds.qos import Policy, Qos

from robonix_api import auth

log = logging.getLogger("robonix_api.dds.writer_trust")
TAG_PREFIX = b"rbnx_deploy="
REFRESH_MIN_S = 0.05  # wall s between discovery re-reads for an unknown writer (a flood costs little)


def deployment_tag(token: str) -> bytes:
    """The deployment's USER_DATA entry: ``rbnx_deploy=`` + 32 hex chars of SHA-256 over the token."""
    digest = hashlib.sha256(b"robonix-dds-writer\0" + token.encode()).hexdigest()[:32]
    return TAG_PREFIX + digest.encode()


def participant_user_data(base: bytes) -> bytes:
    """``base`` (rmw's ``enclave=/;``) plus the deployment's tag entry when this process holds a token."""
    token = auth.current_token()
    return base + deployment_tag(token) + b";" if token else base


def participant_qos(base: bytes) -> Qos:
    """The QoS a provider's participant is created with: USER_DATA from :func:`participant_user_data`."""
    return Qos(Policy.Userdata(participant_user_data(base)))


class WriterTrust:
    """Answers "does this sample's writer belong to the deployment?" from DDS discovery data."""

    def __init__(self, participant: Any, tag: bytes) -> None:
        self.tag = tag
        self._pubs = BuiltinDataReader(participant, BuiltinTopicDcpsPublication)
        self._parts = BuiltinDataReader(participant, BuiltinTopicDcpsParticipant)
        self._lock = threading.Lock()
        self._verdict: dict[int, bool] = {}   # publication handle -> trusted
        self._writer_part: dict[int, Any] = {}  # publication handle -> participant key
        self._part_tag: dict[Any, bytes] = {}   # participant key -> USER_DATA
        self._refreshed = -1e9

    @classmethod
    def for_deployment(cls, participant: Any) -> WriterTrust | None:
        """Trust for the deployment named by ``ROBONIX_DEPLOY_TOKEN``; None when no token is set."""
        token = auth.current_token()
        return cls(participant, deployment_tag(token)) if token else None

    def _refresh(self) -> None:
        for p in self._pubs.take(N=1024):
            self._writer_part[int(p.sample_info.instance_handle)] = p.participant_key
        for q in self._parts.take(N=1024):
            ud = q.qos[Policy.Userdata] if q.qos is not None else None
            self._part_tag[q.key] = bytes(ud.data) if ud is not None else b""

    def allowed(self, publication_handle: int | None) -> bool:
        """True when the writer's participant carries the deployment tag. A writer not yet seen in
        discovery is refused (and looked up again on its next sample, at most every ``REFRESH_MIN_S``)."""
        if publication_handle is None:
            return False
        h = int(publication_handle)
        with self._lock:
            if h in self._verdict:
                return self._verdict[h]
            now = time.monotonic()
            if now - self._refreshed >= REFRESH_MIN_S:
                self._refreshed = now
                self._refresh()
            part = self._writer_part.get(h)
            if part is None or part not in self._part_tag:
                return False  # discovery has not told us yet: decide on a later sample
            ok = self.tag in self._part_tag[part].split(b";")
            self._verdict[h] = ok
            return ok
