"""The byte-exact S-Bus vectors of spec pcd4h3.md §9.4 against a running PCD on a real pty, in
the manual's example installation (BAR = BAF = 200, FMAH3 = 48) and the default one."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.pcd4h3.helpers import Station, hexbytes

ACK = "B5 02 00 00 23 F4"
NAK = "B5 02 00 01 33 D5"


def exchange(pcd: Station, request: str, reply: str, wire: str | None = None) -> None:
    """Send ``request`` (raw; ``wire`` is its stuffed form where the spec gives it) and expect
    ``reply`` byte for byte on the wire."""
    raw = hexbytes(request)
    if wire is not None:
        pcd.serial.write(hexbytes(wire))
    else:
        pcd.send_raw(raw)
    expected = hexbytes(reply)
    got = pcd.serial.read(len(expected))
    assert got == expected, f"{got.hex(' ')} != {expected.hex(' ')}"


@pytest.mark.parametrize(("name", "request_", "reply", "wire"), [
    ("V1", "B5 00 01 0E 05 00 CF 00 00 03 E8 8C 42", ACK, None),
    ("V2", "B5 00 01 0B 03 00 CF 00 01 B3 8A", ACK, None),
    ("V3", "B5 00 01 0B 03 00 E4 00 01 C5 BD", ACK, "B5 00 01 0B 03 00 E4 00 01 C5 01 BD"),
    ("V8", "B5 00 01 0E 05 00 D4 00 00 04 1B 22 0C", ACK, None),
    ("V10", "B5 00 01 0E 05 00 CD C8 00 00 47 EF F0", ACK, None),
    ("V11", "B5 00 01 0E 15 00 C8 00 00 00 96 00 00 00 32 00 00 00 32 00 00 01 F4 00 00 00 0F F9 49", ACK, None),
    ("V18", "B5 00 01 0E 05 00 B5 00 00 00 C5 77 F6", ACK, "B5 00 01 0E 05 00 C5 00 00 00 00 C5 01 77 F6"),
    ("V16", "B5 00 01 38 C9 FE", ACK, None),
])
def test_writes_and_commands_are_acknowledged(pcd: Station, name: str, request_: str, reply: str,
                                              wire: str | None) -> None:
    exchange(pcd, request_, reply, wire)


def test_status_flags_after_axinit_v4_v5(pcd: Station) -> None:
    exchange(pcd, "B5 00 01 02 04 00 C8 48 6E", "B5 01 01 36 1F")  # V4: OnDest = 1
    exchange(pcd, "B5 00 01 02 22 00 C8 7C 08", "B5 01 01 00 00 00 00 64 22")  # V5: the whole field


def test_mcw_reads_back_v8_v9(pcd: Station) -> None:
    exchange(pcd, "B5 00 01 0E 05 00 D4 00 00 04 1B 22 0C", ACK)
    exchange(pcd, "B5 00 01 06 00 00 D4 8D E2", "B5 01 00 00 04 1B 7D 62")


def test_signal_register_after_axinit_v12(pcd: Station) -> None:
    assert pcd.write_flags(227, 1) == b"\x00\x00"  # FRdSR
    pcd.sim.advance(0.02)
    exchange(pcd, "B5 00 01 06 00 00 DB 7C 0D", "B5 01 00 00 40 84 CE 3C")


def test_module_inputs_v13(pcd: Station) -> None:
    exchange(pcd, "B5 00 01 03 0F 00 30 A0 3C", "B5 01 00 66 76 C4")


def test_status_station_v14_v15_and_nak_v17(pcd: Station) -> None:
    exchange(pcd, "B5 00 01 1B DD FF", "B5 01 52 5C 89")
    exchange(pcd, "B5 00 01 1D BD 39", "B5 01 01 36 1F")
    body = hexbytes("B5 00 01 47")  # an unsupported command
    from devsim.devices.pcd4h3.sbus import crc16

    pcd.send_raw(body + crc16(body).to_bytes(2, "big"))
    assert pcd.serial.read(6) == hexbytes(NAK)
    # why the station said NAK is in its event log (what `devsim ctl watch` and the MQTT events show)
    assert pcd.sim.runtime.call(lambda: pcd.sim.device.events[-1][1]) == "nak: command 47h is not supported"
    assert pcd.call(0x06, bytes((64,)) + (0).to_bytes(2, "big")) == b"\x00\x01"  # 65 registers: NAK
    assert pcd.sim.runtime.call(lambda: pcd.sim.device.events[-1][1]) == "nak: at most 32 registers per telegram"


def test_stuffing_in_the_crc_v19(pcd: Station) -> None:
    """V19: read R 26: the request's CRC holds B5h, sent as C5h 00h; R 26 is free memory (0)."""
    pcd.serial.write(hexbytes("B5 00 01 06 00 00 1A C5 00 60"))
    assert pcd.receive(4)[2:6] == bytes(4)


def test_example_1_move_and_actual_position_v1_v2_v3_v6(pcd: Station) -> None:
    """V1, V2, V3 start the move to 100 mm; after OnDest, FRdAP gives R 213 = 1000 (V6)."""
    exchange(pcd, "B5 00 01 0E 05 00 CF 00 00 03 E8 8C 42", ACK)
    exchange(pcd, "B5 00 01 0B 03 00 CF 00 01 B3 8A", ACK)
    exchange(pcd, "B5 00 01 0B 03 00 E4 00 01 C5 BD", ACK, "B5 00 01 0B 03 00 E4 00 01 C5 01 BD")
    pcd.sim.advance(0.02)
    assert pcd.read_flags(200, 35)[0] == 0 and pcd.read_flags(207) == [0] and pcd.read_flags(228) == [0]
    assert pcd.sim.run_until(lambda d: d.read("axis.1.OnDest"), 8.0)
    assert pcd.sim.now() == pytest.approx(6.34, abs=0.1)
    pcd.write_flags(221, 1)  # FRdAP
    pcd.sim.advance(1.0)
    exchange(pcd, "B5 00 01 06 00 00 D5 9D C3", "B5 01 00 00 03 E8 3B 89")
    assert pcd.read_registers(213, 7) == [1000, 0, 0, 0, 0, 0, 0]  # V7: all read registers (only FRdAP ran)


def test_default_installation_v20_v21(make: Callable[..., Station]) -> None:
    pcd = make({"h3def": {}})
    exchange(pcd, "B5 00 01 0E 05 07 D7 00 00 03 E8 42 74", ACK)
    exchange(pcd, "B5 00 01 0B 03 07 D7 00 01 08 65", ACK)
    pcd.sim.advance(0.02)
    assert pcd.sim.read("axis.1.trace")[-1] == "C:1F D:00 02 D:00 01 D:86 A0"


def test_silence_for_crc_errors_other_stations_and_broadcasts(pcd: Station) -> None:
    pcd.send_raw(hexbytes("B5 00 01 1B DD FE"))  # CRC wrong
    pcd.send_raw(hexbytes("B5 00 02 1B") + b"\x00\x00")  # another station (and a wrong CRC)
    from devsim.devices.pcd4h3.sbus import crc16

    body = hexbytes("B5 00 FF 0E 05 00 CF 00 00 00 07")  # broadcast: R 207 := 7, no answer
    pcd.send_raw(body + crc16(body).to_bytes(2, "big"))
    exchange(pcd, "B5 00 01 1B DD FF", "B5 01 52 5C 89")  # the first answer is this one
    assert pcd.read_registers(207) == [7]


def test_diagnostics_block_and_run_stop(pcd: Station) -> None:
    """§9.6.2, §9.6.3: AxHndlg calls count one per cycle while the PCD runs, not while stopped
    (43h) or halted; the diagnostics registers are read-only (NAK); while stopped the flags stay
    pending; run (2Fh) goes on."""
    pcd.sim.advance(1.0)
    calls = pcd.read_registers(4011)[0]
    assert calls == pytest.approx(100, abs=2)
    assert pcd.call(0x43) == b"\x00\x00" and pcd.call(0x1B, data_bytes=1) == b"S"
    assert pcd.write_flags(228, 1) == b"\x00\x00"  # FStart: pending while stopped
    pcd.sim.advance(1.0)
    assert pcd.read_registers(4011)[0] == calls and pcd.read_flags(228) == [1]
    assert pcd.call(0x2F) == b"\x00\x00" and pcd.call(0x1B, data_bytes=1) == b"R"
    pcd.sim.advance(1.0)
    assert pcd.read_registers(4011)[0] == pytest.approx(calls + 100, abs=2) and pcd.read_flags(228) == [0]
    assert pcd.write_registers(4000, 1) == b"\x00\x01"  # NAK: read-only
    assert pcd.write_flags(8000, 1) == b"\x00\x01"
    assert pcd.read_registers(4002, 2) == [0, 0]  # actual and set position, counts
