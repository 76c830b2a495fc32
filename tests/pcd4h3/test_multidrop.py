"""PCD4.H3 stations on one serial S-Bus line in a plant file (spec pcd4h3.md §9.2: "RS-232/RS-485
half duplex. Station number 0…253 (default 1) … A PCD answers only telegrams addressed to its
station"), as SERS drives and GMS96 cards share a bus."""

from __future__ import annotations

import serial

from devsim.devices.pcd4h3.sbus import crc16
from devsim.scenario.plant import plant_running
from devsim.scenario.schema import PlantSpec
from tests.pcd4h3.helpers import EXAMPLE


def read_station(port: serial.Serial, station: int) -> bytes:
    """S-Bus 1Dh, read the station number (V15), to ``station``: its reply, or b"" (silence)."""
    request = bytes((0xB5, 0x00, station, 0x1D))
    port.write(request + crc16(request).to_bytes(2, "big"))
    return port.read(5)


def test_stations_on_one_bus_answer_each_to_its_own_number() -> None:
    """A device is on a bus by its first port, here ``sbus`` (by ``transport`` or ``ports``):
    the plant served a PCD put on a bus neither there nor anywhere (it took the bus members by a
    port ``main``, which a PCD4.H3 does not have), and ``ports: {sbus: {bus: …}}`` was refused
    as "only the main port can be on a bus"."""
    spec = PlantSpec.parse({
        "devices": [
            {"name": "p1", "kind": "pcd4h3", "transport": {"bus": "line"}, "config": {**EXAMPLE, "station": 1}},
            {"name": "p2", "kind": "pcd4h3", "ports": {"sbus": {"bus": "line"}}, "config": {**EXAMPLE, "station": 2}},
        ],
        "buses": [{"name": "line"}],
    })
    with plant_running(spec) as plant:
        assert [row.split(": ")[0] for row in plant.describe()] == [
            "p1.ether_udp", "p1.ether_tcp", "p2.ether_udp", "p2.ether_tcp", "line (p1, p2)"]
        assert plant.port_of("p2") == "line"
        with serial.Serial(plant.path("line"), 9600, timeout=1) as port:
            assert read_station(port, 1) == bytes.fromhex("B5 01 01 36 1F")  # (V15)
            assert read_station(port, 2) == serial_reply_of(2)
            port.timeout = 0.2
            assert read_station(port, 3) == b""  # nobody's


def serial_reply_of(station: int) -> bytes:
    body = bytes((0xB5, 0x01, station))
    return body + crc16(body).to_bytes(2, "big")
