"""An Ether-S-Bus client nobody on this project wrote, digimat.saia from PyPI, against the PCD on
a real UDP port: it reads registers, flags and the PCD status, writes a target and the command
flags, and sees the move end (spec pcd4h3.md §9.3, §9.4; the default installation, BAR = BAF =
2000)."""

from __future__ import annotations

import socket
import time
from collections.abc import Callable, Iterator
from typing import Any

import pytest
from digimat.saia import SAIANode

from devsim.scenario.plant import plant_running
from devsim.scenario.schema import PlantSpec

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning:digimat")  # its threads use isSet()


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def until(condition: Callable[[], Any], timeout: float = 10.0) -> Any:
    """Wait for a condition the client's own threads make true (it polls in the background)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = condition()
        if value:
            return value
        time.sleep(0.01)
    raise AssertionError("condition not met in time")


@pytest.fixture
def pcd() -> Iterator[tuple[Any, Any]]:
    spec = PlantSpec.parse({"devices": [{"name": "pcd", "kind": "pcd4h3", "config": {"response_delay_ms": 0}}]})
    with plant_running(spec, virtual=True) as plant:
        port = int(plant.port("pcd.ether_udp").rpartition(":")[2])
        node = SAIANode(253, port=free_udp_port(), autostart=True, scanner=False, localIfaceIpAddr="127.0.0.1")
        try:
            yield plant, node.servers.declare("127.0.0.1", lid=1, port=port)
        finally:
            node.stop()


def test_digimat_saia_reads_and_commands_an_axis(pcd: tuple[Any, Any]) -> None:
    plant, server = pcd
    dest = server.registers.declare(2007)
    assert dest.read() == 1000  # Example 1's DestP (G-16)
    on_dest = server.flags.declare(2000)
    assert on_dest.read() is True
    status = server.registers.declare(2019)  # RSigB is 0 until FRdSR: a read register
    assert status.read() == 0
    dest.value = 1500
    until(lambda: plant.runtime.read("pcd", "axis.1.DestP") == 1500)
    server.flags.declare(2007).value = True  # FLdDA
    server.flags.declare(2028).value = True  # FStart
    until(lambda: plant.runtime.read("pcd", "axis.1.FStart") is True)
    plant.runtime.advance(0.05)
    until(lambda: on_dest.read() is False)  # (read() answers from its cache while it asks again)
    plant.runtime.advance(10.0)
    until(lambda: on_dest.read() is True)
    assert abs(plant.runtime.read("pcd", "axis.1.position") - 150_000) <= 3
