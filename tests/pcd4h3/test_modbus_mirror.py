"""The PCD's media over Modbus, as spec pcd4h3.md §9.8 lays them out (the Modbus facade's
``mirror`` layout): coil n = flag F n, discrete input n = input I n, holding registers 2n, 2n+1 =
register R n (raw 32 bits, high word first; MCFac as its FFP pattern), input registers a read-only
mirror; unit id = the S-Bus station."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest
from pymodbus.client import ModbusTcpClient

from devsim.scenario.schema import PlantSpec
from tests.facades.test_modbus import modbus_tcp


@pytest.fixture
def pcd() -> Iterator[tuple[Any, ModbusTcpClient]]:
    spec = PlantSpec.parse({"devices": [
        {"name": "pcd", "kind": "pcd4h3", "modbus": {"tcp": {"port": 0}, "layout": "mirror"}}]})
    with modbus_tcp(spec, "pcd") as both:
        yield both


def test_example_1_over_modbus(pcd: tuple[Any, ModbusTcpClient]) -> None:
    plant, client = pcd
    assert client.read_holding_registers(2 * 2005, count=2, device_id=1).registers == [0xC800, 0x0047]  # 100.0
    assert not client.write_registers(2 * 2007, [0, 1000], device_id=1).isError()  # DestP := 1000
    assert not client.write_coil(2007, True, device_id=1).isError()  # FLdDA
    assert not client.write_coil(2028, True, device_id=1).isError()  # FStart: FC 05, coil 2028, FF00h (§9.8)
    plant.runtime.advance(0.05)
    assert client.read_coils(2007, count=1, device_id=1).bits[0] is False  # executed
    assert client.read_coils(2000, count=1, device_id=1).bits[0] is False  # OnDest: moving
    plant.runtime.advance(7.0)
    assert client.read_coils(2000, count=1, device_id=1).bits[0] is True
    assert abs(plant.runtime.read("pcd", "axis.1.position") - 100_000) <= 3
    assert client.read_input_registers(2 * 2007, count=2, device_id=1).registers == [0, 1000]
    assert client.write_register(2 * 2007 + 1, 500, device_id=1).isError() is False  # FC 06: one half
    assert plant.runtime.read("pcd", "axis.1.DestP") == 500


def test_limits_of_the_mirror(pcd: tuple[Any, ModbusTcpClient]) -> None:
    _plant, client = pcd
    assert client.read_discrete_inputs(9, count=2, device_id=1).bits[:2] == [True, True]  # LS1x, LS2x (FMAH3 0)
    beyond = client.read_holding_registers(8192, count=2, device_id=1)
    assert beyond.isError() and beyond.exception_code == 2
    diagnostics = client.write_registers(2 * 4000, [0, 1], device_id=1)  # the read-only diagnostics block
    assert diagnostics.isError() and diagnostics.exception_code == 3


def test_the_unit_id_is_the_s_bus_station() -> None:
    """Spec §9.8: "Unit id = S-Bus station": a PCD configured as station 7 answers unit 7 (and
    0xFF/0, which address a TCP server itself); unit 1 is another device, behind no gateway."""
    spec = PlantSpec.parse({"devices": [
        {"name": "pcd", "kind": "pcd4h3", "config": {"station": 7},
         "modbus": {"tcp": {"port": 0}, "layout": "mirror"}}]})
    with modbus_tcp(spec, "pcd") as (_plant, client):
        assert client.read_holding_registers(2 * 2005, count=2, device_id=7).registers == [0xC800, 0x0047]
        other = client.read_holding_registers(2 * 2005, count=2, device_id=1)
        assert other.isError() and other.exception_code == 0x0B
    spec = PlantSpec.parse({"devices": [
        {"name": "pcd", "kind": "pcd4h3", "config": {"station": 7},
         "modbus": {"tcp": {"port": 0}, "layout": "mirror", "unit": 9}}]})
    with modbus_tcp(spec, "pcd") as (_plant, client):  # a unit the plant names wins
        assert not client.read_holding_registers(2 * 2005, count=2, device_id=9).isError()
