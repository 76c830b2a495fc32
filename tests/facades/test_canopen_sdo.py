"""The SDO server frame by frame (issue 35; CiA 301 §7.2.4.3, the SDO protocols, and §7.2.4.3.17,
the abort codes): request frames handed straight to the server of a sers node, its answers
compared with the protocol's rules written here as a small oracle (command specifiers in bits
5 … 7, the toggle bit 4, ``n`` unused bytes, ``e`` expedited, ``s`` size indicated, ``c`` no more
segments).  In-process, no bus: the same server answers canopen's master in test_canopen*.py."""

from __future__ import annotations

import functools
import logging
import struct
from collections.abc import Iterator

import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from devsim.core.clock import VirtualClock
from devsim.core.registry import device_class
from devsim.facades.canopen_node import CanopenFacade
from devsim.facades.canopen_od import DEVICE_TYPE
from devsim.facades.canopen_sdo import DevsimSdoServer

NODE = 5
ABORT = 0x80
INVALID_COMMAND, TOGGLE, NOT_IN_OD = 0x05040001, 0x05030000, 0x06020000
READ_ONLY, NO_SUBINDEX, LENGTH, GENERAL = 0x06010002, 0x06090011, 0x06070010, 0x08000000

NAME = b"devsim sers"  # 1008h, 11 bytes: a segmented upload of two segments
VOLTAGE = 0x203D  # quantity.supply_voltage, REAL64, read-write
PULSES = 0x200E  # encoder.pulses, INTEGER32, write-only
TIMER = 0x1800  # TPDO1 communication parameter: sub-index 5, its event timer, UNSIGNED16
INPUT = 0x201C  # input.I1, BOOLEAN (no number type: any announced size is taken)
#: Writable objects of a number type and their size in bytes.
NUMBERS = {(TIMER, 5): 2, (PULSES, 0): 4, (VOLTAGE, 0): 8}


@functools.cache
def _facade() -> CanopenFacade:
    """One sers node for the module (its object dictionary takes a while to build).  mutmut runs
    every mutant in a process that imported this module before, cache and all: what a mutant
    must reach is built in the test (each :class:`Server` is)."""
    return CanopenFacade(device_class("sers")(clock=VirtualClock(), config={}), NODE)


class Server:
    """A fresh SDO server of the sers node; ``send`` hands it one request and returns its answers."""

    def __init__(self) -> None:
        self.facade = _facade()
        self.device = self.facade.device
        self.sdo = DevsimSdoServer(0x600 + NODE, 0x580 + NODE, self.facade.node)
        self.answers: list[bytes] = []
        self.sdo.send_response = lambda data: self.answers.append(bytes(data))  # type: ignore[method-assign]

    def send(self, *request: int | bytes) -> list[bytes]:
        frame = b"".join(bytes((part,)) if isinstance(part, int) else part for part in request)
        before = len(self.answers)
        self.sdo.on_request(0x600 + NODE, frame, 0.0)
        return self.answers[before:]

    def close(self) -> None:
        self.sdo.reset()


@pytest.fixture
def server() -> Iterator[Server]:
    s = Server()
    try:
        yield s
    finally:
        s.close()


def mux(index: int, subindex: int = 0) -> bytes:
    return struct.pack("<HB", index, subindex)


def abort(index: int, subindex: int, code: int) -> list[bytes]:
    """The abort transfer request (§7.2.4.3.17): 80h, the multiplexer, the code, little-endian."""
    return [struct.pack("<BHBL", ABORT, index, subindex, code)]


def segment(toggle: int, data: bytes, last: bool) -> int:
    """A segment's command byte: the toggle (bit 4), ``n`` = 7 - len (bits 1 … 3), ``c`` (bit 0)."""
    return toggle << 4 | (7 - len(data)) << 1 | last


PAD = bytes(4)


def test_a_request_is_eight_bytes_shorter_ones_are_ignored(server: Server) -> None:
    frame = bytes((0x40,)) + mux(0x1000) + PAD
    for length in range(8):
        assert server.send(frame[:length]) == []
    assert server.send(frame) == [bytes((0x43,)) + mux(0x1000) + struct.pack("<L", DEVICE_TYPE)]
    assert server.send(frame + b"\xff") == [bytes((0x43,)) + mux(0x1000) + struct.pack("<L", DEVICE_TYPE)]


@settings(deadline=None)  # (the first example may build the module's cached node)
@given(command=st.integers(0, 255))
@example(command=0x00)  # download segment
@example(command=0x20)  # initiate download
@example(command=0x40)  # initiate upload
@example(command=0x60)  # upload segment
@example(command=0x80)  # abort
@example(command=0xA0)  # block upload
@example(command=0xC0)  # block download
@example(command=0xE0)  # ccs 7
@example(command=0xFF)
def test_each_command_specifier_on_a_server_without_a_transfer(command: int) -> None:
    """Bits 5 … 7 decide (bits 0 … 4 are the protocol's flags): on a server with no transfer in
    progress, a segment is aborted 0504 0001h naming 0000h/00h (it carries no multiplexer), a block
    transfer or ccs 7 likewise naming its own multiplexer; a client's abort gets no answer."""
    s = Server()
    try:
        ccs = command >> 5
        frame = bytes((command,)) + mux(0x1018, 1) + PAD  # vendor-ID, read-only UNSIGNED32
        answers = s.send(frame)
        if ccs in (0, 3):
            assert answers == abort(0, 0, INVALID_COMMAND)
        elif ccs in (5, 6, 7):
            assert answers == abort(0x1018, 1, INVALID_COMMAND)
        elif ccs == 4:
            assert answers == []
        elif ccs == 2:
            assert answers == [bytes((0x43,)) + mux(0x1018, 1) + PAD]
        else:  # a download into a read-only object, expedited or not
            assert answers == abort(0x1018, 1, READ_ONLY)
        assert s.sdo.transfer is None
    finally:
        s.close()


@pytest.mark.parametrize(("index", "subindex", "size"), [(INPUT, 0, 1), (TIMER, 5, 2), (0x1000, 0, 4)])
def test_an_expedited_upload_says_how_many_bytes_are_unused(server: Server, index: int, subindex: int,
                                                             size: int) -> None:
    """Initiate upload response (§7.2.4.3.5): 43h | n << 2, n = 4 - size; the data in bytes 4 … 7."""
    answer, = server.send(0x40, mux(index, subindex), PAD)
    assert answer[:4] == bytes((0x43 | (4 - size) << 2,)) + mux(index, subindex)
    assert server.sdo.transfer is None


def test_a_write_only_object_is_not_uploaded(server: Server) -> None:
    assert server.send(0x40, mux(PULSES), PAD) == abort(PULSES, 0, 0x06010001)


def test_a_segmented_upload_to_its_end_then_no_more_segments(server: Server) -> None:
    assert server.send(0x40, mux(0x1008), PAD) == [bytes((0x41,)) + mux(0x1008) + struct.pack("<L", len(NAME))]
    assert server.sdo.transfer == "upload"
    assert server.send(0x60, bytes(7)) == [bytes((segment(0, NAME[:7], False),)) + NAME[:7]]
    assert server.sdo.transfer == "upload"
    assert server.send(0x70, bytes(7)) == [bytes((segment(1, NAME[7:], True),)) + NAME[7:] + bytes(3)]
    assert server.sdo.transfer is None
    assert server.send(0x60, bytes(7)) == abort(0, 0, INVALID_COMMAND)


def test_a_toggle_error_ends_the_upload_and_names_its_object(server: Server) -> None:
    server.send(0x40, mux(0x1008), PAD)
    assert server.send(0x70, bytes(7)) == abort(0x1008, 0, TOGGLE)  # the first segment has toggle 0
    assert server.sdo.transfer is None
    assert server.send(0x60, bytes(7)) == abort(0, 0, INVALID_COMMAND)


def test_an_upload_after_an_unfinished_one_starts_afresh(server: Server) -> None:
    """An expedited upload in the middle of a segmented one ends it: no segment of the old one."""
    server.send(0x40, mux(0x1008), PAD)
    assert server.send(0x40, mux(0x1000), PAD)[0][0] == 0x43
    assert server.sdo.transfer is None
    assert server.send(0x60, bytes(7)) == abort(0, 0, INVALID_COMMAND)
    assert server.send(0x20, mux(VOLTAGE), PAD) == [bytes((0x60,)) + mux(VOLTAGE) + PAD]
    assert server.send(0x40, mux(0x1000), PAD)[0][0] == 0x43  # a download in progress ends too
    assert server.sdo.transfer is None
    assert server.send(0x00, bytes(7)) == abort(0, 0, INVALID_COMMAND)


def test_a_segmented_download_to_its_end(server: Server) -> None:
    value = struct.pack("<d", 50.0)
    assert server.send(0x21, mux(VOLTAGE), struct.pack("<L", 8)) == [bytes((0x60,)) + mux(VOLTAGE) + PAD]
    assert server.sdo.transfer == "download"
    assert server.send(0x60, bytes(7)) == abort(0, 0, INVALID_COMMAND)  # no upload segment in a download
    server.send(0x21, mux(VOLTAGE), struct.pack("<L", 8))
    assert server.send(segment(0, value[:7], False), value[:7]) == [bytes((0x20,)) + bytes(7)]
    assert server.sdo.transfer == "download"
    assert server.send(segment(1, value[7:], True), value[7:], bytes(6)) == [bytes((0x30,)) + bytes(7)]
    assert server.sdo.transfer is None
    assert server.device.read("quantity.supply_voltage") == 50.0
    assert server.send(0x00, bytes(7)) == abort(0, 0, INVALID_COMMAND)


def test_no_download_segment_in_an_upload(server: Server) -> None:
    server.send(0x40, mux(0x1008), PAD)
    assert server.send(0x00, bytes(7)) == abort(0, 0, INVALID_COMMAND)


@pytest.mark.parametrize("size", [1, 2, 3, 4])
def test_an_expedited_download_of_each_size(server: Server, size: int) -> None:
    """Initiate download request (§7.2.4.3.3): 23h | n << 2, n = 4 - size; no segments follow."""
    index, subindex = {1: (INPUT, 0), 2: (TIMER, 5), 3: (TIMER, 5), 4: (PULSES, 0)}[size]
    data = bytes((1, 0, 0, 0))[:size]
    answers = server.send(0x23 | (4 - size) << 2, mux(index, subindex), data.ljust(4, b"\0"))
    if size == 3:  # three bytes for an UNSIGNED16
        assert answers == abort(index, subindex, LENGTH)
    else:
        assert answers == [bytes((0x60,)) + mux(index, subindex) + PAD]
    assert server.sdo.transfer is None
    assert server.send(0x00, bytes(7)) == abort(0, 0, INVALID_COMMAND)


@pytest.mark.parametrize(("index", "subindex", "size"), [(TIMER, 5, 2), (0x607A, 0, 4)])  # (607Ah: target position)
def test_an_expedited_download_that_does_not_say_its_size(server: Server, index: int, subindex: int,
                                                         size: int) -> None:
    """Initiate download request with e = 1, s = 0 (22h): "d contains unspecified number of bytes
    to be downloaded" (§7.2.4.3.3): the object takes as many as its type has."""
    value = 0x0102_0304 & (1 << 8 * size) - 1
    data = value.to_bytes(size, "little").ljust(4, b"\xee")  # (the bytes beyond, whatever they are)
    assert server.send(0x22, mux(index, subindex), data) == [bytes((0x60,)) + mux(index, subindex) + PAD]
    assert server.send(0x40, mux(index, subindex), PAD)[0][4:4 + size] == value.to_bytes(size, "little")


@settings(deadline=None)  # (the first example may build the module's cached node)
@given(number=st.sampled_from(sorted(NUMBERS)), announced=st.integers(0, 16), sized=st.booleans())
@example(number=(VOLTAGE, 0), announced=8, sized=True)
@example(number=(VOLTAGE, 0), announced=7, sized=True)
@example(number=(VOLTAGE, 0), announced=9, sized=True)
@example(number=(TIMER, 5), announced=2, sized=True)
@example(number=(TIMER, 5), announced=1, sized=True)
@example(number=(TIMER, 5), announced=3, sized=True)
@example(number=(PULSES, 0), announced=4, sized=True)
@example(number=(PULSES, 0), announced=5, sized=False)
@example(number=(PULSES, 0), announced=0, sized=True)
def test_a_segmented_download_announces_the_size_of_its_number(number: tuple[int, int], announced: int,
                                                                 sized: bool) -> None:
    """Checked at the initiation: a size indicated (``s``) that is not the number's own size is
    refused 0607 0010h before any segment; without ``s`` the size is not checked there."""
    s = Server()
    try:
        answers = s.send(0x20 | sized, mux(*number), struct.pack("<L", announced))
        if sized and announced != NUMBERS[number]:
            assert answers == abort(*number, LENGTH)
            assert s.sdo.transfer is None
        else:
            assert answers == [bytes((0x60,)) + mux(*number) + PAD]
            assert s.sdo.transfer == "download"
    finally:
        s.close()


@pytest.mark.parametrize("byte", [0, 1, 2, 0xFF])
def test_a_boolean_takes_0_and_1_only(server: Server, byte: int) -> None:
    """CiA 301's BOOLEAN is 0 (false) or 1 (true): another value is out of range (0609 0030h)."""
    answers = server.send(0x2F, mux(INPUT), bytes((byte, 0, 0, 0)))
    if byte > 1:
        assert answers == abort(INPUT, 0, 0x06090030)
    else:
        assert answers == [bytes((0x60,)) + mux(INPUT) + PAD]
        assert server.device.read("input.I1") is bool(byte)


@settings(deadline=None)  # (the first example may build the module's cached node)
@given(announced=st.integers(0, 16))
def test_a_segmented_download_of_no_number_type_takes_any_size_announced(announced: int) -> None:
    s = Server()
    try:
        assert s.send(0x21, mux(INPUT), struct.pack("<L", announced)) == [bytes((0x60,)) + mux(INPUT) + PAD]
    finally:
        s.close()


@pytest.mark.parametrize(("frame", "expected"), [
    ((0x21, mux(0x5FFF), PAD), abort(0x5FFF, 0, NOT_IN_OD)),  # no such object
    ((0x21, mux(0x1018, 7), PAD), abort(0x1018, 7, NO_SUBINDEX)),  # no such sub-index of a record
    ((0x21, mux(0x1018, 1), struct.pack("<L", 4)), abort(0x1018, 1, READ_ONLY)),  # a record's read-only entry
    ((0x21, mux(0x1000), struct.pack("<L", 4)), abort(0x1000, 0, READ_ONLY)),
    ((0x20, mux(0x1008), PAD), abort(0x1008, 0, READ_ONLY)),
])
def test_a_segmented_download_is_refused_at_its_initiation(server: Server, frame: tuple[int | bytes, ...],
                                                             expected: list[bytes]) -> None:
    assert server.send(*frame) == expected
    assert server.sdo.transfer is None
    assert server.send(0x00, bytes(7)) == abort(0, 0, INVALID_COMMAND)


@pytest.mark.parametrize("frame", [
    (0x40, mux(0x1000, 1), PAD),  # an expedited upload of the device type
    (0x40, mux(0x1008, 1), PAD),  # a segmented upload of the device name
    (0x2B, mux(0x6040, 1), struct.pack("<HH", 0x06, 0)),  # an expedited download, size given
    (0x22, mux(0x6040, 1), struct.pack("<HH", 0x06, 0)),  # an expedited download, size not given
    (0x21, mux(VOLTAGE, 1), struct.pack("<L", 8)),  # a segmented download
])
def test_an_object_of_one_value_has_no_sub_index_but_0(server: Server, frame: tuple[int | bytes, ...]) -> None:
    """A VAR object is its sub-index 00h alone (CiA 301, object code VAR: a single value): a request to
    another sub-index of it is aborted 0609 0011h, no such sub-index, and writes nothing."""
    index, subindex = struct.unpack_from("<HB", frame[1])
    controlword, voltage = server.facade.node.sdo[0x6040].raw, server.device.read("quantity.supply_voltage")
    assert server.send(*frame) == abort(index, subindex, NO_SUBINDEX)
    assert server.sdo.transfer is None
    assert (server.facade.node.sdo[0x6040].raw, server.device.read("quantity.supply_voltage")) == (controlword, voltage)


def test_a_segmented_download_into_a_record_entry(server: Server) -> None:
    """In a record the sub-index names the object whose size counts: 1400h/02h, RPDO1's
    transmission type, is an UNSIGNED8."""
    assert server.send(0x21, mux(0x1400, 2), struct.pack("<L", 1)) == [bytes((0x60,)) + mux(0x1400, 2) + PAD]
    assert server.send(0x21, mux(0x1400, 2), struct.pack("<L", 2)) == abort(0x1400, 2, LENGTH)


def test_a_client_abort_ends_the_transfer_without_an_answer(server: Server) -> None:
    server.send(0x40, mux(0x1008), PAD)
    assert server.send(0x80, mux(0x1008), struct.pack("<L", 0x05040000)) == []
    assert server.sdo.transfer is None and server.sdo.last_received_error == 0x05040000
    assert server.send(0x60, bytes(7)) == abort(0, 0, INVALID_COMMAND)


def test_reset_communication_ends_a_transfer(server: Server) -> None:
    server.send(0x21, mux(VOLTAGE), struct.pack("<L", 8))
    server.sdo.reset()
    assert server.sdo.transfer is None and server.sdo._buffer is None
    assert server.send(0x00, bytes(7)) == abort(0, 0, INVALID_COMMAND)


def test_a_fault_of_the_server_is_the_general_error_and_it_goes_on(server: Server, caplog: pytest.LogCaptureFixture,
                                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    def broken(name: str) -> object:
        raise RuntimeError("a bug")

    server.send(0x40, mux(0x1008), PAD)
    monkeypatch.setattr(server.device, "read", broken)
    with caplog.at_level(logging.ERROR, logger="devsim.facades.canopen_sdo"):
        assert server.send(0x40, mux(VOLTAGE), PAD) == abort(VOLTAGE, 0, GENERAL)
    assert server.sdo.transfer is None
    assert [r.getMessage() for r in caplog.records] == [f"SDO request 40{VOLTAGE & 0xFF:02x}{VOLTAGE >> 8:02x}0000000000"]
    monkeypatch.undo()
    assert server.send(0x40, mux(0x1000), PAD) == [bytes((0x43,)) + mux(0x1000) + struct.pack("<L", DEVICE_TYPE)]


def test_abort_without_a_code_is_the_general_error(server: Server) -> None:
    server.send(0x40, mux(0x1008), PAD)
    server.sdo.abort()
    assert server.answers[-1] == abort(0x1008, 0, GENERAL)[0]
    assert server.sdo.transfer is None


@settings(deadline=None)  # (the first example may build the module's cached node)
@given(index=st.integers(0, 0xFFFF), subindex=st.integers(0, 0xFF), ccs=st.sampled_from([5, 6, 7]))
@example(index=0xFFFF, subindex=0xFF, ccs=5)
@example(index=0x8000, subindex=0x80, ccs=6)
@example(index=0x7FFF, subindex=0x7F, ccs=7)
def test_an_abort_names_any_multiplexer_as_sent(index: int, subindex: int, ccs: int) -> None:
    """The multiplexer is an UNSIGNED16 index and an UNSIGNED8 sub-index, little-endian, in
    bytes 1 … 3 of the request and of its abort."""
    s = Server()
    try:
        assert s.send(ccs << 5, mux(index, subindex), PAD) == abort(index, subindex, INVALID_COMMAND)
        if index not in s.facade.od:
            assert s.send(0x21, mux(index, subindex), PAD) == abort(index, subindex, NOT_IN_OD)
    finally:
        s.close()


def test_a_fresh_server_listens_on_600h_answers_on_580h_and_has_no_transfer() -> None:
    """CiA 301 §7.3.5 (the pre-defined connection set): SDO requests on 600h + node-ID, answers on
    580h + node-ID; before any request there is no transfer and an abort names 0000h/00h."""
    facade = CanopenFacade(_facade().device, NODE)  # (not the cached one: built by this test)
    try:
        assert (facade.sdo.rx_cobid, facade.sdo.tx_cobid) == (0x600 + NODE, 0x580 + NODE)
    finally:
        facade.close()
    s = Server()
    assert s.sdo.transfer is None
    s.sdo.abort(TOGGLE)
    assert s.answers == abort(0, 0, TOGGLE)


def test_a_generic_masters_start_up_list_of_position_objects(server: Server) -> None:
    """The position objects of CiA 402-2 a master's start-up SDO list writes, frame by frame: 6065h
    and 6067h (UNSIGNED32, 23h), 6066h and 6068h (UNSIGNED16, 2Bh), 60F2h (UNSIGNED16) each
    answered 60h with their multiplexer and read back as written (4Bh/43h); a positioning option code
    the node does not honour (a change immediately option, 0004h) is aborted 0609 0030h, naming
    60F2h/00h, and an expedited download without its size (22h) gives 6068h its 2 bytes."""
    server.facade.drive.reset()  # (the module's node: its power-on values)
    writes = {0x6065: (0x23, struct.pack("<L", 1000)), 0x6066: (0x2B, struct.pack("<H", 50) + bytes(2)),
              0x6067: (0x23, struct.pack("<L", 10)), 0x6068: (0x2B, struct.pack("<H", 20) + bytes(2)),
              0x60F2: (0x2B, struct.pack("<H", 0x0000) + bytes(2))}
    for index, (command, data) in writes.items():
        assert server.send(command, mux(index), data) == [bytes((0x60,)) + mux(index) + PAD], hex(index)
    for index, (command, data) in writes.items():
        upload = 0x43 if command == 0x23 else 0x4B
        assert server.send(0x40, mux(index), PAD) == [bytes((upload,)) + mux(index) + data], hex(index)
    assert server.send(0x2B, mux(0x60F2), struct.pack("<H", 0x0004) + bytes(2)) == abort(0x60F2, 0, 0x06090030)
    assert server.send(0x40, mux(0x60F2), PAD) == [bytes((0x4B,)) + mux(0x60F2) + PAD]
    assert server.send(0x22, mux(0x6068), struct.pack("<L", 0xFFFF_0007)) == [bytes((0x60,)) + mux(0x6068) + PAD]
    assert server.send(0x40, mux(0x6068), PAD) == [bytes((0x4B,)) + mux(0x6068) + struct.pack("<H", 7) + bytes(2)]
    server.facade.drive.reset()
