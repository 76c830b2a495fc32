"""The facade against a bare pymodbus server (issue 29): the same generated requests to both, over
Modbus TCP on sockets and over Modbus RTU on ptys, must get the same response bytes, exceptions
included.  The device is a PCD4.H3 served with its mirror layout (flags, inputs and registers as
plain tables, spec pcd4h3 §9.8); the pymodbus server (3.16, pinned) holds a copy of the same map
in a ``SimDevice``.  Writes go to both, so the two stay equal request after request.

Where pymodbus itself departs from the standard, the standard wins: such a request is not sent to
pymodbus, its answer is the standard's (:data:`EXCLUSIONS`, each with its section of the Modbus
Application Protocol Specification V1.1b3 or the Messaging on TCP/IP Implementation Guide V1.0b).
"""

from __future__ import annotations

import asyncio
import os
import select
import socket
import struct
import threading
import tty
from collections.abc import Callable, Iterator
from typing import Any, Protocol

import pytest
import serial
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st
from pymodbus.framer import FramerRTU, FramerType
from pymodbus.server import ModbusSerialServer, ModbusTcpServer
from pymodbus.simulator import DataType, SimData, SimDevice

from devsim.core.registry import device_class
from devsim.facades.modbus_map import BITS, ModbusMap, to_words
from devsim.scenario.plant import plant_running
from devsim.scenario.schema import PlantSpec

BAUD = 115200
EXAMPLES = settings(max_examples=120, deadline=None, derandomize=True,
                    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])

#: Function code -> (offset of the quantity in the PDU, its range) for the reads and writes:
#: §6.1 and §6.2 1 … 2000, §6.3 and §6.4 1 … 125, §6.11 1 … 1968, §6.12 1 … 123, §6.17 1 … 125
#: to read (offset 3) and 1 … 121 to write (offset 7).
QUANTITIES: dict[int, list[tuple[int, int]]] = {
    1: [(3, 2000)], 2: [(3, 2000)], 3: [(3, 125)], 4: [(3, 125)], 15: [(3, 1968)], 16: [(3, 123)],
    23: [(3, 125), (7, 121)],
}


#: The functions the facade implements (docs/facades/modbus.md); every other code is unknown to it.
#: (43, Read Device Identification, is not compared: the bare server has pymodbus's identity, not
#: the device's; tests/facades/test_modbus_ident.py checks it against §6.21.)
FUNCTIONS = frozenset((1, 2, 3, 4, 5, 6, 15, 16, 23, 43))


def exception(pdu: bytes, code: int) -> bytes:
    return bytes((pdu[0] | 0x80, code))


def unknown_function(pdu: bytes, sizes: dict[str, int]) -> bytes | None:
    """§7 code 01 with the function code plus 80h (§4.2): pymodbus answers ``80 01`` to a code it
    does not know, and answers codes the facade does not implement (08, 14h …), which a server may
    leave out (§6: "an implementation" supports a subset)."""
    return exception(pdu, 1) if pdu[0] not in FUNCTIONS else None


def quantity_out_of_range(pdu: bytes, sizes: dict[str, int]) -> bytes | None:
    """§6.1–6.4, 6.11, 6.12, 6.17 (the state diagrams): a quantity out of range is 03, checked
    before the addresses.  pymodbus's decoder raises on it, and its server answers ``80 01`` on
    TCP and nothing on RTU; it takes up to 2000 coils for FC 15, where §6.11 allows 1968."""
    for at, most in QUANTITIES.get(pdu[0], []):
        if not 1 <= struct.unpack_from(">H", pdu, at)[0] <= most:
            return exception(pdu, 3)
    return None


def coil_value_neither_on_nor_off(pdu: bytes, sizes: dict[str, int]) -> bytes | None:
    """§6.5: FF00h is ON, 0000h OFF, "all other values are illegal" (03); pymodbus takes any
    non-zero value as ON."""
    if pdu[0] == 5 and pdu[3:5] not in (b"\xff\x00", b"\x00\x00"):
        return exception(pdu, 3)
    return None


def read_write_reading_outside(pdu: bytes, sizes: dict[str, int]) -> bytes | None:
    """§6.17 (the state diagram): both ranges are checked before anything is done, so a read range
    outside the map is 02 with nothing written; pymodbus writes first, then fails the read."""
    if pdu[0] == 23:
        address, quantity = struct.unpack_from(">HH", pdu, 1)
        if address + quantity > sizes["holding"]:
            return exception(pdu, 2)
    return None


#: The PCD's read-only diagnostics block (config ``diagnostics``, here its last register and flag):
#: the device refuses a write there, and the facade answers 03 as for every value the device
#: refuses (docs/facades/modbus.md); the bare pymodbus copy has no device behind it.
READ_ONLY = {"holding": (8190, 8192), "coil": (8191, 8192)}


def written_range(pdu: bytes) -> tuple[str, int, int] | None:
    """The table, first address and quantity a write request touches (None: not a write)."""
    if pdu[0] in (5, 6):
        return ("coil" if pdu[0] == 5 else "holding"), struct.unpack_from(">H", pdu, 1)[0], 1
    if pdu[0] in (15, 16):
        address, quantity = struct.unpack_from(">HH", pdu, 1)
        return ("coil" if pdu[0] == 15 else "holding"), address, quantity
    if pdu[0] == 23:
        address, quantity = struct.unpack_from(">HH", pdu, 5)
        return "holding", address, quantity
    return None


def into_the_diagnostics_block(pdu: bytes, sizes: dict[str, int]) -> bytes | None:
    written = written_range(pdu)
    if written is None:
        return None
    table, address, quantity = written
    first, end = READ_ONLY[table]
    if address + quantity <= sizes[table] and address < end and first < address + quantity:
        return exception(pdu, 3)
    return None


EXCLUSIONS: list[Callable[[bytes, dict[str, int]], bytes | None]] = [
    unknown_function, quantity_out_of_range, coil_value_neither_on_nor_off, read_write_reading_outside,
    into_the_diagnostics_block]

#: Messaging on TCP/IP §4.4.1.2: 0xFF is the unit id of a server addressed by its IP address, and
#: "the value 0 is also accepted to communicate directly to a MODBUS/TCP device"; the bare pymodbus
#: server knows only its device's id (1), so those requests go to it with unit id 1.
DIRECT_UNITS = (0xFF, 0x00)


def by_the_standard(pdu: bytes, sizes: dict[str, int]) -> bytes | None:
    for rule in EXCLUSIONS:
        if (answer := rule(pdu, sizes)) is not None:
            event(f"answered by the standard: {rule.__name__}")
            return answer
    event(f"compared with pymodbus: function {pdu[0]:02X}")
    return None


def as_holding(ask: Callable[[bytes], bytes], pdu: bytes) -> bytes:
    """The bare server's answer to ``pdu`` (a response PDU).  The mirror serves register n in both
    the holding and the input table (one point, spec pcd4h3 §9.8) where pymodbus keeps two tables,
    so a write to a holding register shows in the input table only on the facade: an FC 04 read is
    asked of pymodbus as FC 03 of the same registers."""
    if pdu[0] != 4:
        return ask(pdu)
    answer = ask(b"\x03" + pdu[1:])
    return bytes((answer[0] & 0x80 | 4,)) + answer[1:]


# -- the requests ----------------------------------------------------------------------------------
def requests(sizes: dict[str, int], unknown: bool = True) -> st.SearchStrategy[bytes]:
    """Request PDUs: mostly the nine functions with addresses in, near and beyond each table's end
    and quantities in and around their limits; some unknown function codes (``unknown``)."""
    word = st.integers(0, 0xFFFF)

    def address(table: str) -> st.SearchStrategy[int]:
        end = sizes[table]
        return st.one_of(st.integers(0, end - 1), st.integers(max(end - 130, 0), end + 2), word)

    def quantity(most: int) -> st.SearchStrategy[int]:
        return st.one_of(st.integers(1, 8), st.integers(1, most), st.sampled_from([0, most, most + 1]), word)

    def read(code: int, table: str, most: int) -> st.SearchStrategy[bytes]:
        return st.builds(lambda a, q: struct.pack(">BHH", code, a, q), address(table), quantity(most))

    def write_coils(a: int, q: int, bits: list[bool]) -> bytes:
        n = min(q, 1968)  # (a PDU is at most 253 bytes, §4.1)
        packed = bytearray((n + 7) // 8)
        for i in range(n):
            packed[i // 8] |= (bits[i % len(bits)] << (i % 8))
        return struct.pack(">BHHB", 15, a, q, len(packed) & 0xFF) + bytes(packed[:255])

    def write_registers(a: int, q: int, values: list[int]) -> bytes:
        n = min(q, 123)
        return struct.pack(f">BHHB{n}H", 16, a, q, 2 * n, *(values[i % len(values)] for i in range(n)))

    def read_write(ra: int, rq: int, wa: int, wq: int, values: list[int]) -> bytes:
        n = min(wq, 121)
        return struct.pack(f">BHHHHB{n}H", 23, ra, rq, wa, wq, 2 * n, *(values[i % len(values)] for i in range(n)))

    values = st.lists(word, min_size=1, max_size=8)
    on_off = st.sampled_from([0xFF00, 0x0000])
    functions = [
        read(1, "coil", 2000), read(2, "discrete", 2000), read(3, "holding", 125), read(4, "input", 125),
        st.builds(lambda a, v: struct.pack(">BHH", 5, a, v), address("coil"), st.one_of(on_off, on_off, word)),
        st.builds(lambda a, v: struct.pack(">BHH", 6, a, v), address("holding"), word),
        st.builds(write_coils, address("coil"), quantity(1968), st.lists(st.booleans(), min_size=1, max_size=16)),
        st.builds(write_registers, address("holding"), quantity(123), values),
        st.builds(read_write, address("holding"), quantity(125), address("holding"), quantity(121), values),
    ]
    if unknown:
        functions.append(st.builds(lambda code, rest: bytes((code,)) + rest, st.sampled_from(UNKNOWN),
                                   st.binary(min_size=0, max_size=8)))
    return st.one_of(*functions)


UNKNOWN = [code for code in range(256) if code not in FUNCTIONS]


# -- the bare pymodbus server ----------------------------------------------------------------------
def same_map(device: Any, mapping: ModbusMap) -> SimDevice:
    """A pymodbus ``SimDevice`` (id 1) holding the device's present values at the map's addresses.
    pymodbus keeps bits in 16-bit words and reads the padding of a table's last word as zeros,
    where §6.1 and §6.2 want exception 02 for an address that does not exist (the facade's
    answer, tests/facades/test_modbus_conformance.py); so each bit table must fill whole words to
    be the same map (the mirror's 8192 flags and 1024 inputs do)."""
    tables: dict[str, list[Any]] = {}
    for table in ("coil", "discrete", "holding", "input"):
        size = mapping.size(table)
        assert size and (table not in BITS or size % 16 == 0)
        tables[table] = [False if table in BITS else 0] * size
    for entry in mapping.entries:
        value = device.read(entry.name)
        if entry.table in BITS:
            tables[entry.table][entry.address] = bool(value)
        else:
            tables[entry.table][entry.address:entry.end] = list(to_words(value, entry.scale))
    blocks = [[SimData(0, values=tables[t], datatype=DataType.BITS if t in BITS else DataType.REGISTERS)]
              for t in ("coil", "discrete", "holding", "input")]
    return SimDevice(1, simdata=(blocks[0], blocks[1], blocks[2], blocks[3]), use_bit_addressing=True)


def sizes_of(mapping: ModbusMap) -> dict[str, int]:
    return {table: mapping.size(table) for table in ("coil", "discrete", "holding", "input")}


#: The mirror's tables (8192 flags, 1024 inputs, 4096 registers as two words each), which the
#: request strategies are built from.
MIRROR = ModbusMap.mirror(device_class("pcd4h3").points)


@pytest.fixture(scope="module")
def loop() -> Iterator[asyncio.AbstractEventLoop]:
    """An event loop in a thread of its own for the bare pymodbus servers."""
    running = asyncio.new_event_loop()
    thread = threading.Thread(target=running.run_forever, daemon=True)
    thread.start()
    try:
        yield running
    finally:
        running.call_soon_threadsafe(running.stop)
        thread.join(5)
        running.close()


PLANT = {"devices": [{"name": "tcp", "kind": "pcd4h3", "config": {"diagnostics": [4095, 8191]},
                      "modbus": {"tcp": {"port": 0}, "layout": "mirror"}},
                     {"name": "rtu", "kind": "pcd4h3", "config": {"diagnostics": [4095, 8191]},
                      "modbus": {"rtu": {}, "layout": "mirror", "line": f"{BAUD} 8N1"}}]}


@pytest.fixture(scope="module")
def plant() -> Iterator[Any]:
    with plant_running(PlantSpec.parse(PLANT), virtual=True) as running:
        yield running


# -- Modbus TCP ------------------------------------------------------------------------------------
class TcpPeer:
    """A raw Modbus TCP client: one request, its response's bytes."""

    def __init__(self, where: tuple[str, int]) -> None:
        self.sock = socket.create_connection(where, timeout=5)

    def ask(self, transaction: int, unit: int, pdu: bytes) -> bytes:
        self.sock.sendall(struct.pack(">HHHB", transaction, 0, len(pdu) + 1, unit) + pdu)
        head = self._exactly(7)
        return head + self._exactly(struct.unpack(">H", head[4:6])[0] - 1)

    def _exactly(self, size: int) -> bytes:
        data = b""
        while len(data) < size:
            chunk = self.sock.recv(size - len(data))
            assert chunk, "connection closed"
            data += chunk
        return data


@pytest.fixture(scope="module")
def tcp_pair(plant: Any, loop: asyncio.AbstractEventLoop) -> Iterator[tuple[TcpPeer, TcpPeer, dict[str, int]]]:
    mapping = ModbusMap.mirror(plant.devices["tcp"].points)
    simdevice = same_map(plant.devices["tcp"], mapping)

    async def start() -> ModbusTcpServer:
        server = ModbusTcpServer(simdevice, address=("127.0.0.1", 0))
        await server.serve_forever(background=True)
        return server

    server = asyncio.run_coroutine_threadsafe(start(), loop).result(10)
    bare_port = server.transport.sockets[0].getsockname()[1]  # type: ignore[union-attr]
    host, _, port = plant.port("tcp.modbus").removeprefix("socket://").rpartition(":")
    facade, bare = TcpPeer((host, int(port))), TcpPeer(("127.0.0.1", bare_port))
    try:
        yield facade, bare, sizes_of(mapping)
    finally:
        facade.sock.close()
        bare.sock.close()
        asyncio.run_coroutine_threadsafe(server.shutdown(), loop).result(10)


@EXAMPLES
@given(pdus=st.lists(requests(sizes_of(MIRROR)), min_size=1, max_size=4),
       unit=st.sampled_from([1, 1, 1, *DIRECT_UNITS]), transaction=st.integers(0, 0xFFFF))
def test_tcp_answers_as_pymodbus_or_the_standard(tcp_pair: tuple[TcpPeer, TcpPeer, dict[str, int]],
                                                 pdus: list[bytes], unit: int, transaction: int) -> None:
    facade, bare, sizes = tcp_pair
    for pdu in pdus:
        answer = facade.ask(transaction, unit, pdu)
        header = struct.pack(">HHHB", transaction, 0, 0, unit)
        expected = by_the_standard(pdu, sizes)
        if expected is None:
            expected = as_holding(lambda p: bare.ask(transaction, 1, p)[7:], pdu)  # (unit FF/0: as id 1)
        assert answer == header[:4] + struct.pack(">HB", len(expected) + 1, unit) + expected, pdu.hex()


# -- Modbus RTU ------------------------------------------------------------------------------------
class SerialLike(Protocol):
    def reset_input_buffer(self) -> None: ...

    def write(self, data: bytes, /) -> Any: ...

    def read(self, size: int, /) -> bytes: ...


class RtuPeer:
    """A raw RTU master on a serial port (a pty): a frame, then the response's bytes by length."""

    def __init__(self, port: SerialLike) -> None:
        self.port = port

    def ask(self, frame: bytes) -> bytes:
        self.port.reset_input_buffer()
        self.port.write(frame + FramerRTU.compute_CRC(frame).to_bytes(2, "big"))
        head = self.port.read(3)
        assert len(head) == 3, f"no answer to {frame.hex()}"
        size = 5 if head[1] & 0x80 else (head[2] + 5 if head[1] in (1, 2, 3, 4, 23) else 8)
        answer = head + self.port.read(size - 3)
        assert len(answer) == size
        return answer


@pytest.fixture(scope="module")
def rtu_pair(plant: Any, loop: asyncio.AbstractEventLoop) -> Iterator[tuple[RtuPeer, RtuPeer, dict[str, int]]]:
    mapping = ModbusMap.mirror(plant.devices["rtu"].points)
    simdevice = same_map(plant.devices["rtu"], mapping)
    master, slave = os.openpty()
    tty.setraw(master)

    async def start() -> ModbusSerialServer:
        server = ModbusSerialServer(simdevice, framer=FramerType.RTU, port=os.ttyname(slave), baudrate=BAUD)
        await server.serve_forever(background=True)
        return server

    server = asyncio.run_coroutine_threadsafe(start(), loop).result(10)
    facade_port = serial.Serial(plant.port("rtu.modbus"), BAUD, timeout=2)
    try:
        yield RtuPeer(facade_port), RtuPeer(PtyMaster(master)), sizes_of(mapping)
    finally:
        facade_port.close()
        asyncio.run_coroutine_threadsafe(server.shutdown(), loop).result(10)
        os.close(master)
        os.close(slave)


class PtyMaster:
    """The master side of the bare server's pty, as the serial port calls RtuPeer makes."""

    def __init__(self, fd: int) -> None:
        self.fd = fd

    def reset_input_buffer(self) -> None:
        while select.select([self.fd], [], [], 0)[0]:
            os.read(self.fd, 1024)

    def write(self, data: bytes) -> None:
        os.write(self.fd, data)

    def read(self, size: int) -> bytes:
        data = b""
        while len(data) < size and select.select([self.fd], [], [], 2)[0]:
            data += os.read(self.fd, size - len(data))
        return data


@EXAMPLES
@given(pdu=requests(sizes_of(MIRROR), unknown=False))
def test_rtu_answers_as_pymodbus_or_the_standard(rtu_pair: tuple[RtuPeer, RtuPeer, dict[str, int]],
                                                 pdu: bytes) -> None:
    facade, bare, sizes = rtu_pair
    expected = by_the_standard(pdu, sizes)
    answer = facade.ask(b"\x01" + pdu)
    if expected is None:
        expected = as_holding(lambda p: bare.ask(b"\x01" + p)[1:-2], pdu)
    frame = b"\x01" + expected
    assert answer == frame + FramerRTU.compute_CRC(frame).to_bytes(2, "big"), pdu.hex()
