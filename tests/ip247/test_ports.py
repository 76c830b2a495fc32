"""The IP247's PG port on a real pty (AS511, vectors §3.6.7 a, b, f) and its PLC side on a real
TCP socket (spec ip247.md §3.7, BCD values of §3.3.2)."""

from __future__ import annotations

import socket
import struct
from typing import Any

import msgspec
import pytest
import serial

from devsim.devices.ip247 import program as lang
from devsim.devices.ip247.client import AgClient, PgClient
from devsim.devices.ip247.machine_data import decode, encode
from tests.ip247.test_machine_data import COM247, MANUAL, SECTION_6_3, words

VECTOR_A = bytes.fromhex("02 10 06 64 02 10 06 16 10 03 10 06 04 46 00 00 10 04".replace(" ", ""))


@pytest.fixture
def module(devsim_device):  # noqa: ANN001, ANN201
    return devsim_device("ip247", {"sys_id": {"module": 11, "slot": 1}})


def pg(module: Any) -> serial.Serial:
    return serial.serial_for_url(module.port_url("pg"), baudrate=9600, parity="E", timeout=5)


def test_vector_a_read_sys_id_byte_by_byte(module: Any) -> None:
    """§3.6.7 (a): every byte of the transaction as the spec lists it."""
    with pg(module) as port:
        steps = [("02", "10 06"), ("64", "02"), ("10 06", "16 10 03"), ("10 06", ""),
                 ("04 46 00 00 10 04", "10 06 02"),
                 ("10 06", "00 04 46 00 00 00 00 00 49 50 32 34 37 20 41 30 32 2E 31 20 00 0B 00 01 00 00 10 03"),
                 ("10 06", "02"), ("10 06", "12 10 03"), ("10 06", "")]
        for sent, expected in steps:
            port.write(bytes.fromhex(sent))
            want = bytes.fromhex(expected)
            assert port.read(len(want)) == want, f"after {sent}"
        assert port.in_waiting == 0


def test_vector_f_unknown_function_is_refused(module: Any) -> None:
    with pg(module) as port:
        port.write(b"\x02")
        assert port.read(2) == b"\x10\x06"
        port.write(b"\x18")
        assert port.read(2) == b"\x10\x15"
        client = PgClient(port)  # the link is idle again: the next transaction works
        assert client.transaction(0x64, bytes((4, 0x46, 0, 0)))[8:14] == b"IP247 "  # type: ignore[index]


def test_a_single_dle_inside_the_parameters_is_refused_at_dle_eot(module: Any) -> None:
    """Spec §3.6.5: an undoubled DLE followed by an unexpected byte gets DLE NAK at the next
    acknowledgement point, the block's DLE EOT; nothing is executed, and the next transaction works."""
    with pg(module) as port:
        for sent, expected in [("02", "10 06"), ("64", "02"), ("10 06", "16 10 03")]:
            port.write(bytes.fromhex(sent))
            assert port.read(len(bytes.fromhex(expected))) == bytes.fromhex(expected), f"after {sent}"
        port.write(bytes.fromhex("10 06 04 46 10 41 00 10 04"))  # "10 41": neither a doubled DLE nor DLE EOT
        assert port.read(2) == b"\x10\x15"
        client = PgClient(port)
        assert client.transaction(0x64, bytes((4, 0x46, 0, 0)))[8:14] == b"IP247 "  # type: ignore[index]


def test_vector_b_and_a_program_through_the_client(module: Any) -> None:
    """§3.6.7 (b): machine data, reference set, program 5, then BA8 Start; the program runs on
    the device clock to its end."""
    module.set("input.ANF1", True)
    module.set("input.END1", True)
    with pg(module) as port:
        client = PgClient(port)
        md = words(COM247)
        answer = client.transaction(0x63, bytes((1, 20, 123, 0)) + struct.pack(">70H", *md))
        assert answer is not None and answer[8] == 0
        assert client.transaction(0x61, bytes.fromhex("01 05 01 01 00 00 00 00 00 00"))[4] == 0  # type: ignore[index]
        record = lang.record_words(5, "%  5 VEKTOR B\nN1 X10 F1000\nN2 M02\n")
        assert client.transaction(0x63, bytes((4, 22, 5, 0)) + struct.pack(f">{len(record)}H", *record))[8:] \
            == bytes(4)
        assert client.transaction(0x61, bytes.fromhex("01 08 01 05 00 00 00 00 00 00")) \
            == bytes.fromhex("00 01 08 01 00 08 02 FF")
        module.advance(5)
        observed = client.transaction(0x62, b"\x01")
        assert observed is not None and observed[7] == 2 and observed[6] & 0x84 == 0x84
        assert struct.unpack(">i", observed[8:12])[0] == 10_000  # X10 (G90: absolute)


@pytest.mark.manual("§2.5.4.6", "with AG BCD-codiert the paths and velocities of the PLC jobs for jog and "
                    "step moves are BCD")
def test_the_plc_side_over_tcp_with_bcd_values(devsim_device) -> None:  # noqa: ANN001
    """§3.7/§3.3.2: absolute pages from the S2 base page; with "AG BCD-codiert" the target
    +120 000 µm arrives as 0012 0000H, 1000 mm/min as word 1000H; not BCD: error 66; machine
    data are never overwritten from the PLC (17)."""
    module = devsim_device("ip247", {"sys_id": {"module": 11}, "base_page": 8}, transport="tcp")
    module.set("input.ANF1", True)
    module.set("input.END1", True)
    md = words(COM247)
    md[47] = 0x0001  # AG BCD-codiert
    host, port = module.port_url("ag").removeprefix("socket://").rsplit(":", 1)
    with AgClient(host, int(port)) as plc:
        assert plc.write_record(8, 20, 123, md)[8] == 0
        assert plc.write_record(8, 20, 123, md, overwrite=True)[4] == 17
        assert plc.operate(8, 5, "Start", b=1)[:6] == bytes((0, 8, 5, 1, 0, 5))
        assert plc.operate(8, 6, "Start", w=0x1000, dd=0x0012_0000)[4] == 0
        module.advance(30)
        assert module.read("axis.1.position") == 120_000
        assert plc.observe(8)[8:12] == struct.pack(">i", 120_000)  # (OBSERVE values are binary)
        assert plc.operate(8, 6, "Start", w=0x1000, dd=0x001A_0000)[4] == 66
        assert plc.operate(7, 6, "Start", w=0x1000, dd=0x0012_0000)[0] == 0x80  # not this module's page


def test_generic_s5_services_read_programs_and_machine_data(devsim_device) -> None:  # noqa: ANN001
    """With ``s5_services``: 18H system parameters, 1BH block list, 1AH B_INFO and 04H read memory as
    an S5 CPU answers them (libnodave's AS511 client reads DBs this way): program 5 is DB 5, the machine
    data stored as DB 123 are DX 123; an unknown block is refused with DLE NAK."""
    module = devsim_device("ip247", {"sys_id": {"module": 11}, "s5_services": True})
    module.set("program.5", "%  5 GENERIC\nN1 X10 F1000\nN2 M02\n")
    module.set("input.ANF1", True)
    module.set("input.END1", True)
    with pg(module) as port:
        client = PgClient(port)
        md = words(COM247)
        client.transaction(0x63, bytes((1, 20, 123, 0)) + struct.pack(">70H", *md))
        system = client.transaction(0x18, b"")
        assert system is not None and len(system) == 45 and system[:5] == bytes(5)
        listing = client.transaction(0x1B, b"\x01")
        assert listing is not None and len(listing) == 1 + 512
        listed = [n for n in range(256) if listing[1 + 2 * n : 3 + 2 * n] != b"\x00\x00"]
        assert listed == [5]
        for kind, number, record in ((0x01, 5, lang.record_words(5, "%  5 GENERIC\nN1 X10 F1000\nN2 M02\n")),
                                     (0x0C, 123, module.read("axis.1.machine_data"))):
            info = client.transaction(0x1A, bytes((kind, number)))
            assert info is not None and info[0] == 0 and info[3:7] == bytes((0x70, 0x70, 0x40 | kind, number))
            address, length = struct.unpack(">H", info[1:3])[0], struct.unpack(">H", info[11:13])[0]
            assert length == 5 + len(record)
            data = client.transaction(0x04, struct.pack(">HH", address, address + 2 * len(record) - 1))
            assert data is not None and data[:5] == bytes(5)
            assert list(struct.unpack(f">{len(record)}H", data[5:])) == record
        port.write(b"\x02")
        assert port.read(2) == b"\x10\x06"
        port.write(b"\x1a")
        assert port.read(1) == b"\x02"
        port.write(b"\x10\x06")
        assert port.read(3) == b"\x16\x10\x03"
        port.write(b"\x10\x06\x01\x09\x10\x04")  # DB 9 does not exist
        assert port.read(2) == b"\x10\x15"
    # why it was refused is in the device's event log (what `devsim ctl watch` and the MQTT events show)
    events = module.runtime.call(lambda: [name for _t, name in module.device.events])
    assert events[-1] == "pg refused_parameters: no such block"


@pytest.mark.manual("§2.5", "machine data from the PLC side are checked by the IP247 only: an axis can hold "
                    "faulty machine data, reported as error 15 with the MD error in the record")
@pytest.mark.manual("§2.5.1.2", "the pulse duration lies in 1 to 31 us and at most half the period of the "
                    "maximum frequency, else MD error 2")
@pytest.mark.manual("§2.5.2.1", "pulses per revolution lie in 12 to 1000, else MD error 5")
@pytest.mark.manual("§2.5.3.4", "the finest travel resolution is 0.001 mm per pulse, else MD error 9")
@pytest.mark.manual("§2.5.3.5", "the maximum frequency lies in 0.040 to 100 kHz, else MD error 3")
@pytest.mark.manual("§2.5.3.6", "the start-stop frequency lies in 0.001 to 10 kHz (below the maximum "
                    "frequency), else MD error 22")
@pytest.mark.manual("§2.5.3.7", "tau lies between 5 ms and 2.6 s (a_min, a_max), else MD error 6")
@pytest.mark.manual("§2.5.3.9", "the backlash compensation lies in 0 to 64.999 mm, else MD error 20")
@pytest.mark.manual("§2.5.3.10", "at machine-data input the limit-switch polarity is checked against the "
                    "inputs (both not actuated), else MD error 19")
@pytest.mark.manual("§2.5.4.1", "the unit is metric (01), 0.1 inch (10) or degree (11), else MD error 11")
@pytest.mark.manual("§2.5.4.2", "each velocity lies in 1 to 65000 and at most the maximum velocity, else MD "
                    "error 4")
@pytest.mark.manual("§2.5.5.1", "SW limit Ende plus the MD tool offset must stay within +99.999999 m, else MD "
                    "error 14")
@pytest.mark.manual("§2.5.5.2", "a zero offset of the machine data that leaves the range of +-99.999999 m is "
                    "refused at input (MD error 13)")
@pytest.mark.manual("§2.5.2.2", "the number of current patterns is 2 x phases (twice that in half step): an "
                    "odd number is MD error 10")
def test_every_md_error_trigger_of_section_6_3_over_tcp(devsim_device) -> None:  # noqa: ANN001
    """§6.3 through the PLC endpoint: each changed record (BA20 after BA21) comes back with its
    MD error in the result and module error 15; the valid §6.1 record with 0."""
    module = devsim_device("ip247", {}, transport="tcp")
    host, port = module.port_url("ag").removeprefix("socket://").rsplit(":", 1)
    with AgClient(host, int(port)) as plc:
        for changes, levels, error in [({}, (True, True), 0), *SECTION_6_3]:
            module.set("input.ANF1", levels[0])
            module.set("input.END1", levels[1])
            plc.delete_record(0, 21, 1)
            answer = plc.write_record(0, 20, 1, encode(msgspec.structs.replace(decode(words(MANUAL)), **changes)))
            assert (answer[8], answer[4]) == (error, 15 if error else 0), changes


def test_vector_6_5_the_manuals_example_program_in_the_directory(module: Any) -> None:
    """§6.5 / §3.4.2: program "BEISPIEL" as DB 1 (25 words); BA65 lists 0001 0019; BA69 reads the
    same record back."""
    text = "%  1 BEISPIEL\nN1 X100 F1000 M10\nN2 M02\n"
    record = lang.record_words(1, text)
    assert len(record) == 25
    with pg(module) as port:
        client = PgClient(port)
        assert client.write_record(4, 22, 1, record)[8:] == bytes(4)
        assert client.read_record(1, 65)[8:] == bytes.fromhex("0001 0019")
        assert client.read_record(2, 69, 1)[8:] == struct.pack(">25H", *record)


def test_a_plc_message_without_a_page_is_malformed(devsim_device) -> None:  # noqa: ANN001
    """§3.7 takes the layouts of §3.6: a message with no page byte has a wrong parameter length,
    ack 82H, nothing executed.  Found by the soak of a real ``devsim run ip247 --tcp 0``: an OBSERVE
    of nothing (length 1, function 62H alone) was taken as absolute page 0 and answered 00H with
    axis 1's values (base page 0)."""
    module = devsim_device("ip247", {"sys_id": {"module": 11}}, transport="tcp")
    host, port = module.port_url("ag").removeprefix("socket://").rsplit(":", 1)
    with AgClient(host, int(port)) as plc:
        for function in (0x61, 0x62, 0x63, 0x64, 0x65):
            assert plc.transaction(function, b"")[:4] == bytes((0x82, 0, 0, 0)), hex(function)
        assert plc.observe(0)[0] == 0  # (page 0 named: axis 1, as before)


def test_a_plc_message_cut_short_takes_what_follows_until_the_connection_ends(devsim_device) -> None:  # noqa: ANN001
    """§3.7 frames a message by its 2-byte length and says nothing of a gap (the real AG side is a
    dual-port RAM: no framing to time out).  A message whose length promises more than was sent
    waits for the rest, and the next message's bytes complete it; the bytes held are bounded by
    the length (at most 65,535).  A new connection starts the framing anew, so a PLC client out of
    step reconnects.  [SIM-CHOICE] no timeout."""
    module = devsim_device("ip247", {"sys_id": {"module": 11}, "base_page": 8}, transport="tcp")
    host, port = module.port_url("ag").removeprefix("socket://").rsplit(":", 1)
    valid = struct.pack(">HBB", 2, 0x62, 8)  # OBSERVE page 8
    with AgClient(host, int(port)) as plc:
        plc.socket.sendall(struct.pack(">HBB", 2 + len(valid), 0x62, 0x99))  # page 99H, then less than promised
        answer = plc.transaction(0x62, b"\x08")[:2]  # (the OBSERVE is the cut message's rest)
        assert answer == bytes((0x80, 0x99))  # the cut message's answer: not this module's page
        plc.socket.sendall(b"\x00\x10")  # a length, and nothing after it
        plc.socket.shutdown(socket.SHUT_WR)  # the PLC leaves ...
        assert plc.socket.recv(100) == b""  # ... and the endpoint has seen it go
    with AgClient(host, int(port)) as plc:  # framing anew: the cut header is forgotten
        assert plc.observe(8)[0] == 0
