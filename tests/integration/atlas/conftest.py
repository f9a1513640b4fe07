"""Fixtures for the atlas tests: an in-process atlas on a free loopback port, clients and raw stubs."""

from __future__ import annotations

import uuid
from collections.abc import Iterator

import grpc
import pytest

from atlas.server import AtlasServer
from robonix_api.atlas_client import AtlasClient
from robonix_api.proto_gen import atlas_pb2_grpc


@pytest.fixture(scope="module")
def atlas_server() -> Iterator[AtlasServer]:
    """One atlas per test module (default 90 s heartbeat timeout, so nothing is evicted mid-test)."""
    server = AtlasServer("127.0.0.1:0")
    server.start()
    yield server
    server.stop(0)


@pytest.fixture
def client(atlas_server: AtlasServer) -> Iterator[AtlasClient]:
    c = AtlasClient(atlas_server.address)
    yield c
    c.close()


@pytest.fixture
def stub(atlas_server: AtlasServer) -> Iterator[atlas_pb2_grpc.AtlasStub]:
    channel = grpc.insecure_channel(atlas_server.address, options=[("grpc.enable_http_proxy", 0)])
    yield atlas_pb2_grpc.AtlasStub(channel)
    channel.close()


@pytest.fixture
def uid() -> str:
    """A suffix that keeps provider ids of tests sharing one atlas apart."""
    return uuid.uuid4().hex[:8]
