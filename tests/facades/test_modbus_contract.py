"""Every kind gets the Modbus facade for free (issue 13, the kit's contract): its map serves over
Modbus TCP, every mapped value reads back as the control API reads it, and every settable number
and switch written with its present value is taken, or refused (exception 03) exactly where the
control API's ``set`` refuses it (a SERS output the variant does not have)."""

from __future__ import annotations

import asyncio

import pytest
from pymodbus.client import AsyncModbusTcpClient

from devsim.core.clock import VirtualClock
from devsim.core.points import BadValue
from devsim.core.registry import device_class, kinds
from devsim.facades.modbus import ModbusFacade, serve_tcp
from devsim.facades.modbus_map import BITS, from_words, to_words


@pytest.mark.parametrize("kind", sorted(kinds()))
def test_every_point_reads_and_writes_over_modbus(kind: str) -> None:
    device = device_class(kind)(clock=VirtualClock(), config={})

    async def check() -> None:
        facade = ModbusFacade(device)
        server, port = await serve_tcp(facade, port=0)
        client = AsyncModbusTcpClient("127.0.0.1", port=port, timeout=5)
        try:
            assert await client.connect()
            for entry in facade.map.entries:
                point = device.points.find(entry.name)
                assert point is not None
                expected = device.read(entry.name) if point.readable else 0
                if entry.table in BITS:
                    read = client.read_coils if entry.table == "coil" else client.read_discrete_inputs
                    answer = await read(entry.address, count=1, device_id=1)
                    assert not answer.isError(), entry
                    assert answer.bits[0] == bool(expected), entry
                    if entry.table == "coil" and point.readable:
                        assert not (await client.write_coil(entry.address, bool(expected), device_id=1)).isError()
                    continue
                read = client.read_holding_registers if entry.table == "holding" else client.read_input_registers
                answer = await read(entry.address, count=2, device_id=1)
                assert not answer.isError(), entry
                assert answer.registers == list(to_words(expected or 0, entry.scale)), entry
                if entry.table == "holding" and point.readable:
                    value = from_words(*answer.registers, entry.scale, entry.type)
                    if device.check(entry.name, value) == value:  # (a value already saturated is not written)
                        written = await client.write_registers(entry.address, answer.registers, device_id=1)
                        if written.isError():  # refused: exactly when the control API refuses it too
                            assert written.exception_code == 3, entry
                            with pytest.raises(BadValue):
                                device.set(entry.name, value)
        finally:
            client.close()
            await server.shutdown()

    try:
        asyncio.run(check())
    finally:
        device.close()
