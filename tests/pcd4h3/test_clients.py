"""Several hosts on the PCD's Ether-S-Bus TCP port (issue 32, item 5; spec pcd4h3.md §9.3): an idle
client no longer blocks the others, each client gets the answers to its own telegrams (also when
they cross within the PCD's response delay), and one client more than the port serves is refused
with a line in the log."""

from __future__ import annotations

import socket
from collections.abc import Iterator
from typing import Any

import pytest

from devsim.devices.pcd4h3.device import ETHER_TCP_HOSTS, Pcd4h3Device
from devsim.devices.pcd4h3.sbus import ether_frame
from devsim.scenario.plant import plant_running
from devsim.scenario.schema import PlantSpec
from tests.pcd4h3.helpers import EXAMPLE


def _plant(**config: Any) -> Any:
    spec = PlantSpec.parse({"devices": [{"name": "pcd", "kind": "pcd4h3", "config": {**EXAMPLE, **config}}]})
    return plant_running(spec)  # real time: the response delay runs on the real clock


@pytest.fixture
def where() -> Iterator[tuple[str, int]]:
    with _plant(response_delay_ms=20) as plant:
        host, _, number = plant.port("pcd.ether_tcp").partition("://")[2].rpartition(":")
        yield host, int(number)


def _station(sequence: int) -> bytes:
    """Read the station number (1Dh), with ``sequence``."""
    return ether_frame(1, sequence, 0, bytes((1, 0x1D)))


def _reply(sock: socket.socket) -> bytes:
    data = b""
    while len(data) < 4 or len(data) < int.from_bytes(data[:4], "big"):
        chunk = sock.recv(4096)
        assert chunk, "closed by the server"
        data += chunk
    return data


def test_the_port_declares_several_hosts() -> None:
    assert {p.name: p.hosts for p in Pcd4h3Device.ports} == {"sbus": 1, "ether_udp": 1, "ether_tcp": ETHER_TCP_HOSTS}
    assert ETHER_TCP_HOSTS > 1


def test_an_idle_client_does_not_block_another(where: tuple[str, int]) -> None:
    with socket.create_connection(where, timeout=5) as idle, socket.create_connection(where, timeout=5) as busy:
        busy.sendall(_station(7))
        reply = _reply(busy)
        assert reply[6:8] == (7).to_bytes(2, "big") and reply[9] == 1
        idle.sendall(_station(8))
        assert _reply(idle)[6:8] == (8).to_bytes(2, "big")


def test_crossing_requests_each_get_their_own_answer(where: tuple[str, int]) -> None:
    clients = [socket.create_connection(where, timeout=5) for _ in range(4)]
    try:
        for round_ in range(5):
            for n, sock in enumerate(clients):  # all sent within the 20 ms response delay
                sock.sendall(_station(100 * n + round_))
            for n, sock in enumerate(clients):
                assert int.from_bytes(_reply(sock)[6:8], "big") == 100 * n + round_
    finally:
        for sock in clients:
            sock.close()


def test_one_client_more_than_the_port_serves_is_refused(where: tuple[str, int],
                                                         capsys: pytest.CaptureFixture[str]) -> None:
    clients = [socket.create_connection(where, timeout=5) for _ in range(ETHER_TCP_HOSTS)]
    try:
        for n, sock in enumerate(clients):
            sock.sendall(_station(n))
            _reply(sock)  # (each one served, so the port counts them all)
        with socket.create_connection(where, timeout=5) as extra:
            try:
                assert extra.recv(100) == b""
            except ConnectionResetError:
                pass
        assert f"it serves {ETHER_TCP_HOSTS} hosts at once" in capsys.readouterr().err
    finally:
        for sock in clients:
            sock.close()
