"""Which UDP sockets a participant opens with the project's loopback config.

Cyclone DDS 0.11 binds the two well-known DDSI unicast ports of a participant (discovery and user
data: 7400 + 250·domain + 10/11 + 2·index) to the wildcard (unspecified) address; there is no option to bind them to
the interface address (upstream: eclipse-cyclonedds#1923, #2090). Every other socket it opens is bound
to 127.0.0.1. The config also sets ``DontRoute``, so nothing it sends leaves through a gateway. This
test pins that picture: a new wildcard socket, or one on a non-loopback address, fails it.
"""

from __future__ import annotations

import ipaddress
import os
import subprocess
import sys
import xml.etree.ElementTree as ET

from robonix_api.dds.config import DEFAULT_CONFIG

LOOPBACK = ipaddress.IPv4Address("127.0.0.1")

PROBE = r"""
import os, sys, time
from cyclonedds.domain import DomainParticipant
from cyclonedds.pub import DataWriter
from cyclonedds.topic import Topic
from robonix_api.dds.config import DEFAULT_CONFIG
os.environ["CYCLONEDDS_URI"] = DEFAULT_CONFIG.as_uri()
from robonix_api.dds.messages import Point
dp = DomainParticipant(int(sys.argv[1]))
w = DataWriter(dp, Topic(dp, "rt/socket_probe", Point))
inodes = set()
for fd in os.listdir("/proc/self/fd"):
    try:
        link = os.readlink(f"/proc/self/fd/{fd}")
    except OSError:
        continue
    if link.startswith("socket:["):
        inodes.add(link[8:-1])
for line in open("/proc/self/net/udp").read().splitlines()[1:]:
    f = line.split()
    if f[9] in inodes:
        print(f[1])
"""


def _addr(hexaddr: str) -> tuple[ipaddress.IPv4Address, int]:
    ip_hex, port_hex = hexaddr.split(":")
    return ipaddress.IPv4Address(bytes(reversed(bytes.fromhex(ip_hex)))), int(port_hex, 16)


def test_loopback_config_sets_dontroute_and_no_multicast() -> None:
    general = {el.tag.split("}")[-1]: (el.text or "").strip()
               for el in ET.parse(DEFAULT_CONFIG).getroot().iter()}
    assert general["DontRoute"] == "true"
    assert general["AllowMulticast"] == "false"


def test_only_the_well_known_unicast_ports_are_wildcard_bound() -> None:
    domain = int(os.environ.get("ROS_DOMAIN_ID", "0"))
    out = subprocess.run([sys.executable, "-c", PROBE, str(domain)], capture_output=True, text=True,
                         timeout=60, check=True).stdout
    socks = [_addr(h) for h in out.split()]
    assert socks, "the participant opened no UDP socket?"
    base = 7400 + 250 * domain
    for ip, port in socks:
        if ip.is_unspecified:  # the wildcard address
            assert 0 <= port - base - 10 < 2 * 120, (ip, port)  # d1 or d3 (10/11) + 2·participant index
        else:
            assert ip == LOOPBACK, (ip, port)
    assert any(ip == LOOPBACK for ip, _ in socks), socks
