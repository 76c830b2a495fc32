"""Read Device Identification, function 43 / MEI type 14 (2Bh / 0Eh), as the Modbus Application
Protocol Specification V1.1b3 §6.21 says, over a real socket and a real pty: pymodbus's client
``read_device_information`` (an independent client) reads the objects, raw frames check the
response layout byte for byte and the errors.

§6.21's rules checked here: the request is ``2B 0E code object``; codes 01 (basic stream:
objects 00 … 02), 02 (regular stream: 00 … 7F), 03 (extended stream) and 04 (one object,
individual access); "an exception code 03 is sent back in the response if the Read Device ID code
is illegal"; with a stream code, "if the Object Id does not match any known object, the server
responds as if object 0 were pointed out (restart at the beginning)"; with code 04 an unknown
object is exception 02; the response is ``2B 0E code conformity more-follows next-object count``
and then id, length, value per object; an object is indivisible, and what does not fit into one
PDU (253 bytes, §4.1) follows in the next transaction (More Follows FF, Next Object Id), More
Follows and Next Object Id 00 otherwise and always with code 04.

The identity the facade gives is docs/facades/modbus.md's: VendorName ``devsim``, ProductCode the
kind, MajorMinorRevision devsim's version, ProductName the kind's description in ASCII,
UserApplicationName the device's name; conformity level 82h (regular, stream and individual).
"""

from __future__ import annotations

import socket
import struct
from collections.abc import Iterator
from typing import Any

import pytest
import serial
from pymodbus.client import ModbusSerialClient, ModbusTcpClient
from pymodbus.framer import FramerRTU

import devsim
from devsim.facades import modbus_pdu
from devsim.scenario.plant import plant_running
from devsim.scenario.schema import PlantSpec

#: §4.1: the largest PDU; the response's head (function code, MEI type, code, conformity level,
#: More Follows, Next Object Id, number of objects) is 7 bytes of it.
MAX_PDU, HEAD = 253, 7
#: The longest device name there is (128 characters, devsim.core.nvram), on the kind with the
#: longest kind and description.
LONG = "x" * 128
SERS = b"Stoegra SERS stepper driver with positioning control (ASCII, RS-232/RS-485)"
POSELESTA = b"ELESTA POSELESTA II/III CNC (tape images on V6/V7 DNC, V8 keyboard, M/S/T bus)"


def expected_objects(kind: str, product: bytes, name: str) -> dict[int, bytes]:
    """docs/facades/modbus.md: 00 VendorName, 01 ProductCode, 02 MajorMinorRevision, 04
    ProductName, 06 UserApplicationName (03 VendorUrl and 05 ModelName not given)."""
    return {0x00: b"devsim", 0x01: kind.encode(), 0x02: devsim.__version__.encode(), 0x04: product,
            0x06: name.encode()}


DRIVE = expected_objects("sers", SERS, "drive")
LONG_OBJECTS = expected_objects("poselesta", POSELESTA, LONG)


#: The objects of each stream, by id, as §6.21 files them: basic 00 … 02, regular (and, with no
#: private objects, extended) 00 … 7F; devsim gives 00, 01, 02, 04, 06.
BASIC_IDS, REGULAR_IDS = [0, 1, 2], [0, 1, 2, 4, 6]


def response(objects: dict[int, bytes], code: int, ids: list[int], following: int | None = None) -> bytes:
    """§6.21's response to stream ``code`` carrying the objects ``ids`` (listed by the test, not
    chosen here), with More Follows FFh and ``following`` as the Next Object Id when given."""
    body = b"".join(bytes((i, len(objects[i]))) + objects[i] for i in ids)
    more = (0x00, 0x00) if following is None else (0xFF, following)
    return bytes((0x2B, 0x0E, code, 0x82, *more, len(ids))) + body


def individual(objects: dict[int, bytes], object_id: int) -> bytes:
    value = objects[object_id]
    return bytes((0x2B, 0x0E, 0x04, 0x82, 0x00, 0x00, 1, object_id, len(value))) + value


def crc(frame: bytes) -> bytes:
    return FramerRTU.compute_CRC(frame).to_bytes(2, "big")


@pytest.fixture(scope="module")
def plant() -> Iterator[Any]:
    spec = PlantSpec.parse({"devices": [{"name": "drive", "kind": "sers", "modbus": {"tcp": {"port": 0}}},
                                        {"name": LONG, "kind": "poselesta", "modbus": {"tcp": {"port": 0}}}]})
    with plant_running(spec, virtual=True) as running:
        yield running


def where(plant: Any, device: str = "drive") -> tuple[str, int]:
    host, _, port = plant.port(f"{device}.modbus").removeprefix("socket://").rpartition(":")
    return host, int(port)


def ask(address: tuple[str, int], pdu: bytes) -> bytes:
    """One request on a fresh connection; the response PDU (the MBAP header checked and cut)."""
    with socket.create_connection(address, timeout=5) as sock:
        sock.sendall(struct.pack(">HHHB", 5, 0, len(pdu) + 1, 1) + pdu)
        head = b""
        while len(head) < 7:
            chunk = sock.recv(7 - len(head))
            assert chunk, "connection closed"
            head += chunk
        transaction, protocol, length, unit = struct.unpack(">HHHB", head)
        assert (transaction, protocol, unit) == (5, 0, 1)
        body = b""
        while len(body) < length - 1:
            chunk = sock.recv(length - 1 - len(body))
            assert chunk, "connection closed"
            body += chunk
        return body


# -- pymodbus's client --------------------------------------------------------------------------
@pytest.fixture
def client(plant: Any) -> Iterator[ModbusTcpClient]:
    host, port = where(plant)
    tcp = ModbusTcpClient(host, port=port, timeout=5)
    assert tcp.connect()
    try:
        yield tcp
    finally:
        tcp.close()


def test_pymodbus_reads_the_basic_identification(client: ModbusTcpClient) -> None:
    """§6.21: code 01 gives the basic objects 00 … 02 (all mandatory) in one response."""
    answer = client.read_device_information(read_code=1, object_id=0, device_id=1)
    assert not answer.isError(), answer
    assert answer.information == {i: DRIVE[i] for i in (0, 1, 2)}
    assert (answer.read_code, answer.conformity, answer.more_follows, answer.next_object_id,
            answer.number_of_objects) == (1, 0x82, 0, 0, 3)


@pytest.mark.parametrize("code", [2, 3])
def test_pymodbus_reads_the_regular_identification(client: ModbusTcpClient, code: int) -> None:
    """Codes 02 and 03: the basic and the regular objects (there are no private, extended ones)."""
    answer = client.read_device_information(read_code=code, object_id=0, device_id=1)
    assert not answer.isError(), answer
    assert answer.information == DRIVE
    assert (answer.read_code, answer.conformity, answer.more_follows, answer.number_of_objects) == (code, 0x82, 0, 5)


@pytest.mark.parametrize("object_id", sorted(DRIVE))
def test_pymodbus_reads_one_object(client: ModbusTcpClient, object_id: int) -> None:
    """Code 04 (individual access): the one object asked for, More Follows 00."""
    answer = client.read_device_information(read_code=4, object_id=object_id, device_id=1)
    assert not answer.isError(), answer
    assert answer.information == {object_id: DRIVE[object_id]}
    assert (answer.read_code, answer.more_follows, answer.next_object_id, answer.number_of_objects) == (4, 0, 0, 1)


def test_pymodbus_reads_the_longest_identity_in_one_transaction(plant: Any) -> None:
    """The longest name a device may have (128 characters) on the kind with the longest
    identity: every object still fits into one response (More Follows 00)."""
    host, port = where(plant, LONG)
    tcp = ModbusTcpClient(host, port=port, timeout=5)
    assert tcp.connect()
    try:
        answer = tcp.read_device_information(read_code=2, object_id=0, device_id=1)
        assert not answer.isError(), answer
        assert (answer.information, answer.more_follows, answer.next_object_id) == (LONG_OBJECTS, 0, 0)
    finally:
        tcp.close()


# -- raw frames: the layout and the errors ------------------------------------------------------------
@pytest.mark.parametrize(("code", "first", "ids"), [(1, 0, BASIC_IDS), (2, 0, REGULAR_IDS), (3, 0, REGULAR_IDS),
                                                   (1, 2, [2]), (2, 4, [4, 6]), (2, 6, [6]), (3, 1, [1, 2, 4, 6])])
def test_a_stream_answers_from_the_object_asked_for(plant: Any, code: int, first: int, ids: list[int]) -> None:
    assert ask(where(plant), bytes((0x2B, 0x0E, code, first))).hex(" ") == response(DRIVE, code, ids).hex(" ")


@pytest.mark.parametrize(("code", "first"), [(1, 0x03), (1, 0x04), (1, 0x80), (2, 0x03), (2, 0x05),
                                             (2, 0x07), (2, 0xFF), (3, 0x90)])
def test_a_stream_from_an_unknown_object_restarts_at_0(plant: Any, code: int, first: int) -> None:
    """§6.21: "the server responds as if object 0 were pointed out (restart at the beginning)"."""
    answer = ask(where(plant), bytes((0x2B, 0x0E, code, first)))
    assert answer.hex(" ") == response(DRIVE, code, BASIC_IDS if code == 1 else REGULAR_IDS).hex(" ")


def test_the_basic_stream_byte_for_byte(plant: Any) -> None:
    """§6.21's response layout: 2B 0E 01, conformity level 82 (regular identification, stream
    and individual access), More Follows 00, Next Object Id 00, 3 objects, each id, length, value."""
    version = devsim.__version__.encode()
    assert ask(where(plant), bytes.fromhex("2B 0E 01 00")) == (
        bytes.fromhex("2B 0E 01 82 00 00 03") + b"\x00\x06devsim" + b"\x01\x04sers"
        + bytes((0x02, len(version))) + version)


def test_the_longest_stream_fits_into_one_response(plant: Any) -> None:
    address = where(plant, LONG)
    answer = ask(address, bytes.fromhex("2B 0E 02 00"))
    assert answer.hex(" ") == response(LONG_OBJECTS, 2, REGULAR_IDS).hex(" ")
    assert answer[4:6] == b"\x00\x00" and len(answer) <= MAX_PDU
    assert ask(address, bytes.fromhex("2B 0E 04 06")).hex(" ") == individual(LONG_OBJECTS, 6).hex(" ")


@pytest.mark.parametrize(("request_pdu", "expected"), [
    pytest.param("2B 0E 00 00", "AB 03", id="code 00: 03"),
    pytest.param("2B 0E 05 00", "AB 03", id="code 05: 03"),
    pytest.param("2B 0E FF 00", "AB 03", id="code FF: 03"),
    pytest.param("2B 0E 04 03", "AB 02", id="object 03 (no VendorUrl): 02"),
    pytest.param("2B 0E 04 05", "AB 02", id="object 05 (no ModelName): 02"),
    pytest.param("2B 0E 04 07", "AB 02", id="object 07 (reserved): 02"),
    pytest.param("2B 0E 04 80", "AB 02", id="object 80 (no private objects): 02"),
    pytest.param("2B 0E 01", "AB 03", id="request too short: 03"),
    pytest.param("2B 0E 01 00 00", "AB 03", id="request too long: 03"),
    pytest.param("2B", "AB 03", id="no MEI type: 03"),
    pytest.param("2B 0D 00 00 00 01 02 03", "AB 01", id="MEI type 0D (CANopen general reference): 01"),
    pytest.param("2B 0F 01 00", "AB 01", id="MEI type 0F (reserved): 01"),
])
def test_the_errors(plant: Any, request_pdu: str, expected: str) -> None:
    """§6.21: an illegal Read Device ID code is 03; with code 04 an object that does not exist is
    02 (Illegal Data Address); §7: the exception response is the function code plus 80h."""
    assert ask(where(plant), bytes.fromhex(request_pdu)).hex(" ") == bytes.fromhex(expected).hex(" ")


def test_one_object_is_cut_to_what_fits_into_one_response() -> None:
    """§6.21: "an object is indivisible": a device name longer than a response can carry (253 −
    7 − 2 bytes) is cut to that length (docs/facades/modbus.md)."""
    from devsim.facades.modbus_ident import identification

    objects = identification("sers", "x", "n" * 300, "1.0")
    assert objects[6] == b"n" * (MAX_PDU - HEAD - 2)


class Named:
    """Tables with just the objects (the other tables are not asked)."""

    def __init__(self, objects: dict[int, bytes]) -> None:
        self.objects = objects

    def identification(self) -> dict[int, bytes]:
        return self.objects


@pytest.mark.parametrize("extra", [-1, 0, 1])
def test_the_last_object_fits_exactly_or_follows(extra: int) -> None:
    """A response of exactly 253 bytes holds every object; one byte more and the last follows."""
    objects = dict(DRIVE)
    objects[6] = b""
    objects[6] = b"n" * (MAX_PDU - len(response(objects, 2, REGULAR_IDS)) + extra)
    answer = modbus_pdu.answer(Named(objects), bytes.fromhex("2B 0E 02 00"))  # type: ignore[arg-type]
    assert answer == (response(objects, 2, [0, 1, 2, 4], following=6) if extra > 0 else response(objects, 2, REGULAR_IDS))
    assert len(answer) <= MAX_PDU
    assert answer[4] == (0xFF if extra > 0 else 0x00)


def test_what_does_not_fit_follows_in_the_next_transaction() -> None:
    """§6.21: "the client must set the Object Id to the value returned by the server in its
    previous response".  devsim's own objects always fit (above); a kind's longer description
    would not: the objects from the first that does not fit follow, and pymodbus's decoder reads
    both answers."""
    from pymodbus.pdu.mei_message import ReadDeviceInformationResponse

    objects = dict(DRIVE)
    objects[4] = b"p" * 150
    objects[6] = b"n" * 100
    tables = Named(objects)
    first = modbus_pdu.answer(tables, bytes.fromhex("2B 0E 02 00"))  # type: ignore[arg-type]
    assert first == response(objects, 2, [0, 1, 2, 4], following=6) and first[4:6] == b"\xff\x06"
    rest = modbus_pdu.answer(tables, bytes.fromhex("2B 0E 02 06"))  # type: ignore[arg-type]
    assert rest == response(objects, 2, [6]) and rest[4:6] == b"\x00\x00"
    read = {}
    for answer in (first, rest):
        decoded = ReadDeviceInformationResponse()
        decoded.decode(answer[1:])
        read.update(decoded.information)
    assert read == objects


@pytest.mark.parametrize("kind", ["gms96", "ip247", "pcd4h3", "poselesta", "sers"])
def test_every_kind_fits_into_one_response(kind: str) -> None:
    """docs/facades/modbus.md: with a device name of 128 characters, the longest there is."""
    from devsim.core.registry import device_class
    from devsim.facades.modbus_ident import identification

    objects = identification(kind, device_class(kind).description, LONG, devsim.__version__)
    answer = modbus_pdu.answer(Named(objects), bytes.fromhex("2B 0E 02 00"))  # type: ignore[arg-type]
    assert answer == response(objects, 2, REGULAR_IDS) and answer[4] == 0x00
    assert all(value.isascii() for value in objects.values())


# -- RTU ---------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def rtu() -> Iterator[str]:
    spec = PlantSpec.parse({"devices": [{"name": "drive", "kind": "sers",
                                         "modbus": {"rtu": {}, "line": "115200 8N1"}}]})
    with plant_running(spec, virtual=True) as running:
        yield running.port("drive.modbus")


def test_rtu_pymodbus_reads_the_identification(rtu: str) -> None:
    client = ModbusSerialClient(rtu, baudrate=115200, parity="N", timeout=2)
    assert client.connect()
    try:
        regular = client.read_device_information(read_code=2, object_id=0, device_id=1)
        assert not regular.isError(), regular
        assert (regular.information, regular.conformity, regular.more_follows) == (DRIVE, 0x82, 0)
        one = client.read_device_information(read_code=4, object_id=4, device_id=1)
        assert one.information == {4: SERS}
        refused = client.read_device_information(read_code=4, object_id=5, device_id=1)
        assert refused.isError() and refused.exception_code == 2
    finally:
        client.close()


def test_rtu_raw_frames(rtu: str) -> None:
    """Address, PDU, CRC (Modbus over Serial Line §2.5.1); a broadcast is not answered (§2.2); a
    request of another MEI type is cut where its CRC holds and answered 01."""
    with serial.Serial(rtu, 115200, timeout=2) as port:
        for request_pdu, expected in (("2B 0E 01 00", response(DRIVE, 1, BASIC_IDS)), ("2B 0E 02 05", response(DRIVE, 2, REGULAR_IDS)),
                                      ("2B 0E 06 00", bytes.fromhex("AB 03")),
                                      ("2B 0E 04 07", bytes.fromhex("AB 02")),
                                      ("2B 0D 00 00 00 01 02 03", bytes.fromhex("AB 01"))):
            frame = b"\x01" + bytes.fromhex(request_pdu)
            port.write(frame + crc(frame))
            answer = b"\x01" + expected
            assert port.read(len(answer) + 2).hex(" ") == (answer + crc(answer)).hex(" "), request_pdu
        broadcast = bytes.fromhex("00 2B 0E 01 00")
        read = bytes.fromhex("01 03 0002 0002")
        port.write(broadcast + crc(broadcast) + read + crc(read))
        answer = bytes.fromhex("01 03 04 0001 09A0")  # the read's (68 000 = 0001 09A0h), nothing before it
        assert port.read(9) == answer + crc(answer)
