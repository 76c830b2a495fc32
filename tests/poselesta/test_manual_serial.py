"""Manual §2.6 (serial interfaces V6, V7, V8) statement by statement, through the real ptys:
baud rates, character frames, the transfer's end, cancelling, the read-in's start and its errors."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import pytest
import serial

from devsim.core.clock import Timer, VirtualClock
from devsim.core.nvram import NonVolatileMemory
from devsim.devices.poselesta.codes import encode, iso_byte
from devsim.devices.poselesta.device import PoselestaDevice
from tests.poselesta.test_ports import O1, open_port, until


def await_tape(cnc: Any, p71: int | None = None) -> None:
    """T7: EXT mode, program P20 pre-selected, V7 waiting for a tape (code P71 when given)."""
    if p71 is not None:
        cnc.set("param.P71", p71)
    cnc.set("panel.mode", "EXTERNAL_OPERATION")
    cnc.set("panel.program", 20)
    cnc.set("v7.transfer", "input")


@pytest.fixture
def cnc(devsim_device):  # noqa: ANN001, ANN201
    return devsim_device("poselesta")


def bytes_out(cnc: Any, port: str) -> int:
    """The bytes the control has put on ``port`` so far (what the line has taken from it)."""
    return int(cnc.runtime.line_status(cnc.name, port)["bytes_out"])


def bytes_in(cnc: Any, port: str) -> int:
    return int(cnc.runtime.line_status(cnc.name, port)["bytes_in"])


def _output_on_v7(cnc: Any, program: str) -> None:
    cnc.set("program.P20", program)
    cnc.set("panel.mode", "EXTERNAL_OPERATION")
    cnc.set("panel.program", 20)
    cnc.set("v7.transfer", "output")


# -- §2.6.2.1 the printer ---------------------------------------------------------------------
@pytest.mark.manual("§2.6.2.1", "Drucker: Baud-Rate: 1200 fest programmiert (Parameter P 68 hat keinen Einfluss)")
@pytest.mark.parametrize(("variant", "p68"), [("III", 0), ("III", 5), ("II", 4), ("II", 5)])
def test_the_printer_port_runs_at_1200_baud_whatever_p68_says(devsim_device, variant: str, p68: int) -> None:  # noqa: ANN001
    """On POS II too, where P68 = 4 and 5 are no rate of the tape devices (it refused the printer)."""
    cnc = devsim_device("poselesta", {"variant": variant})
    cnc.set("param.P68", p68)  # 110 or 4800 baud for the tape devices
    cnc.set("program.P03", "N1 X1")
    cnc.set("panel.mode", "EXTERNAL_MEDIUM")
    cnc.set("panel.program", 3)
    with serial.serial_for_url(cnc.port_url("v6"), baudrate=1200, stopbits=2, timeout=5) as printer:
        cnc.set("v6.transfer", "printer")
        assert cnc.runtime.line_status(cnc.name, "v6")["device"]["baudrate"] == 1200
        cnc.advance(0.0205)  # "%" CR: 2 characters of 12 bits at 1200 baud = 20 ms
        assert bytes_out(cnc, "v6") == 2
        cnc.advance(0.82 + 0.0100)  # the 820 ms carriage return, then one CR at 1200 baud
        assert bytes_out(cnc, "v6") == 3
        assert printer.read(3) == b"%\r\r"


@pytest.mark.manual("§2.6.2.1", "Drucker: P 69 = 0 sxxxxxxxOPSS (ASCII mit parity): 12 bits a character")
@pytest.mark.manual("§2.6.1.2", "Drucker: sxxxxxxxOSS (MSB = 0) oder sxxxxxxxOPSS (mit parity)")
@pytest.mark.parametrize(("p69", "bits"), [(0, 12), (1, 11)])
def test_the_printer_frame_has_an_msb_of_0_and_parity_by_p69(cnc: Any, p69: int, bits: int) -> None:
    cnc.set("param.P69", p69)
    cnc.set("program.P03", "N1 X1")
    cnc.set("panel.mode", "EXTERNAL_MEDIUM")
    cnc.set("panel.program", 3)
    with open_port(cnc, "v6") as printer:
        cnc.set("v6.transfer", "printer")
        cnc.advance(1.5 * bits / 1200)
        assert bytes_out(cnc, "v6") == 1  # the first character has left, the second not yet
        cnc.advance(0.9 * bits / 1200)
        assert bytes_out(cnc, "v6") == 2
        assert printer.read(2) == b"%\r"  # the MSB 0 whatever P69: 7-bit ASCII on the pty


@pytest.mark.parametrize(("config", "printout"), [
    ({}, b"%\r\r\rN 1\rX 1.000\rN 2\rY 2.000\r#\rM 30\r"),
    ({"printer_block_separator": "#"}, b"%\r\r\rN 1\rX 1.000\r#\rN 2\rY 2.000\r#\r#\rM 30\r"),
], ids=["skip_mark", "separator"])
def test_the_printer_prints_the_skip_mark_or_a_block_separator(devsim_device, config: dict[str, Any],  # noqa: ANN001
                                                               printout: bytes) -> None:
    """Spec G-PRN-HASH: the '#' line after block 1 of the manual's printout is the skip mark of a
    skipped block (default), or with printer_block_separator a line after every block."""
    cnc = devsim_device("poselesta", config)
    cnc.set("program.P03", "N1 X1\nN2 Y2 #")
    cnc.set("panel.mode", "EXTERNAL_MEDIUM")
    cnc.set("panel.program", 3)
    with open_port(cnc, "v6") as printer:
        cnc.set("v6.transfer", "printer")
        cnc.advance(15.0)
        assert cnc.read("v6.state") == "done"
        assert printer.read(len(printout)) == printout and printer.in_waiting == 0


# -- §2.6.1.2 the frames of the tape ports ----------------------------------------------------
@pytest.mark.manual("§2.6.1.2", "ISO-Code: sxxxxxxxPSS (mit parity): 11 bits a character")
@pytest.mark.manual("§2.6.1.2", "ASCII-Code: sxxxxxxxSS: 10 bits a character")
@pytest.mark.manual("§2.6.1.1", "Bei POSELESTA II/III werden generell 2 Stop-Bits gesendet")
@pytest.mark.parametrize(("p71", "bits"), [(0, 11), (1, 10)])
def test_dnc_output_leaves_one_character_per_frame_of_its_code(cnc: Any, p71: int, bits: int) -> None:
    cnc.set("param.P71", p71)
    with open_port(cnc, "v7") as host:
        _output_on_v7(cnc, "N1 X10.5 Y-3\nN2 G00 X0 Y0 M02")
        cnc.advance(10.5 * bits / 1200)  # 10.5 frames: 10 characters have left (11-bit frames: 9 of ASCII)
        assert bytes_out(cnc, "v7") == 10
        assert host.read(10) == encode("%\r\nN1X10.5", p71 == 0)


@pytest.mark.manual("§2.6.3", "Baud-Rate: Mit Parameter P 70 wählbar 0 = 110 … 5 = 4800 Baud")
@pytest.mark.parametrize(("p70", "baud"), [(0, 110), (1, 300), (2, 600), (3, 1200), (4, 2400), (5, 4800)])
def test_the_dnc_baud_rate_follows_p70(cnc: Any, p70: int, baud: int) -> None:
    cnc.set("param.P70", p70)
    with serial.serial_for_url(cnc.port_url("v7"), baudrate=baud, stopbits=2, timeout=5) as host:
        _output_on_v7(cnc, "N1 X1")
        assert cnc.runtime.line_status(cnc.name, "v7")["device"]["baudrate"] == baud
        cnc.advance(3.5 * 11 / baud)
        assert bytes_out(cnc, "v7") == 3
        assert host.read(3) == encode("%\r\n", True)


# -- cancelling -------------------------------------------------------------------------------
@pytest.mark.manual("§2.6.3", "Das Uebertragungsende ist mit M 30 und CR gekennzeichnet (a cancelled output "
                    "sends no M 30)")
def test_cancelling_an_output_stops_the_tape_at_once(cnc: Any) -> None:
    with open_port(cnc, "v7") as host:
        _output_on_v7(cnc, "N1 X10.5 Y-3\nN2 G00 X0 Y0 M02")
        cnc.advance(5.5 * 11 / 1200)
        cnc.set("v7.transfer", "idle")
        assert cnc.read("v7.state") == "cancelled"
        cnc.advance(2.0)
        assert bytes_out(cnc, "v7") == 5
        assert host.read(5) == encode("%\r\nN1", True)
        assert host.read(1) == b""  # nothing after the cancel: no M30


@pytest.mark.manual("§2.6.3", "Das Uebertragungsende ist mit M 30 und CR gekennzeichnet (the output ends "
                    "when its last character has left)")
def test_an_output_is_done_when_its_last_character_has_left(cnc: Any) -> None:
    tape = encode("%\r\nN1X1.000\r\nM30\r\n", True)
    with open_port(cnc, "v7") as host:
        _output_on_v7(cnc, "N1 X1")
        cnc.advance((len(tape) - 0.5) * 11 / 1200)
        assert cnc.read("v7.state") == "sending"
        cnc.advance(0.5 * 11 / 1200 + 1e-6)
        assert cnc.read("v7.state") == "done"
        assert host.read(len(tape)) == tape


# -- the read-in's start ------------------------------------------------------------------------
@pytest.mark.manual("§2.6.3", "Die Datenübertragung beginnt mit einem %-Zeichen. Alle vorgängig eintreffenden "
                    "Zeichen werden nicht berücksichtigt.")
def test_a_leader_of_well_formed_characters_before_percent_is_ignored(cnc: Any) -> None:
    await_tape(cnc)
    with open_port(cnc, "v7") as host:
        host.write(b"\x00" * 20 + encode("TAPE 7 N1 X9\r\n", True) + b"\xff" * 3 + encode("%\rN1 X1\rM30\r", True))
        until(lambda: cnc.read("v7.state") == "done", "the read-in ends with M30")
    assert cnc.read("program.P20") == "N 1 X 1.000"


@pytest.mark.parametrize("honour_xoff", [False, True])
def test_xoff_pauses_an_output_only_with_honour_xoff(devsim_device, honour_xoff: bool) -> None:  # noqa: ANN001
    """Spec §3.6, G-FLOW: the control has no handshake, an output runs to its end whatever the host
    sends (DC3 is discarded); with honour_xoff DC3 (either code) holds it after the character being
    sent, DC1 lets it go on."""
    cnc = devsim_device("poselesta", {"honour_xoff": honour_xoff})
    char = 11 / 1200  # ISO: 11 bits a character
    with open_port(cnc, "v7") as host:
        _output_on_v7(cnc, "N1 X10.5 Y-3\nN2 G00 X0 Y0 M02")
        cnc.advance(5.5 * char)
        host.write(b"\x93")  # DC3 with its even parity (ISO)
        until(lambda: bytes_in(cnc, "v7") == 1, "the line has taken the XOFF")
        sent = bytes_out(cnc, "v7")
        cnc.advance(1.0)
        assert (bytes_out(cnc, "v7") == sent) is honour_xoff
        host.write(b"\x11")  # DC1
        until(lambda: bytes_in(cnc, "v7") == 2, "the line has taken the XON")
        cnc.advance(1.0)
        assert cnc.read("v7.state") == "done" and cnc.read("v7.discarded") == 2
        assert host.read(len(O1)) == encode(O1.decode("ascii"), True)  # the whole tape, nothing lost


@pytest.mark.parametrize(("config", "after_pause"), [({}, "receiving"), ({"rx_timeout_s": 2.0}, "failed")])
def test_a_read_in_waits_for_ever_unless_rx_timeout_s_is_set(devsim_device, config: dict[str, Any],  # noqa: ANN001
                                                             after_pause: str) -> None:
    """Spec G-TIMEOUT: the control has no read-in timeout; with rx_timeout_s a read-in that hears
    nothing that long after its last byte fails as a read-in does, the blocks before kept."""
    cnc = devsim_device("poselesta", config)
    await_tape(cnc)
    cnc.advance(1.5)  # the start counts as heard: 1.5 s of silence before the tape
    with open_port(cnc, "v7") as host:
        host.write(encode("%\rN1 X1\r", True))
        until(lambda: cnc.read("v7.blocks") == 1, "the first block is stored")
        cnc.advance(1.9)
        assert cnc.read("v7.state") == "receiving"
        cnc.advance(60.0)
        assert cnc.read("v7.state") == after_pause
    assert cnc.read("program.P20") == "N 1 X 1.000"
    assert (cnc.read("panel.message") == "WERTBEREICHES-UEBERLAUF") is (after_pause == "failed")


@pytest.mark.manual("§2.6", "Wird vor dem Einlesen eines Programmes eine falsche Baud-Rate gewählt, erscheint am "
                    "Bildschirm: WERTBEREICHES-UEBERLAUF")
@pytest.mark.parametrize("p71", [0, 1])
@pytest.mark.parametrize("host_baud", [110, 300, 4800])
def test_a_read_in_at_the_wrong_baud_rate_ends_with_the_overflow_message(cnc: Any, p71: int, host_baud: int) -> None:
    cnc.set("param.P71", p71)  # the control listens at 1200 baud (P70 = 3)
    await_tape(cnc)
    tape = encode("%\r\nN1X10.5Y-3\r\nN2G00X0Y0M02\r\nM30\r\n", p71 == 0)
    with serial.serial_for_url(cnc.port_url("v7"), baudrate=host_baud, stopbits=2, timeout=5) as host:
        host.write(tape)
        until(lambda: cnc.read("v7.state") == "failed", "the garbled tape stops the read-in")
    assert cnc.read("panel.message") == "WERTBEREICHES-UEBERLAUF"
    assert cnc.read("programs") == []


@pytest.mark.manual("§2.6", "Wird vor dem Einlesen eines Programmes eine falsche Baud-Rate gewählt, erscheint am "
                    "Bildschirm: WERTBEREICHES-UEBERLAUF (on an ASCII port, after %: a byte that is neither ASCII nor "
                    "an ISO character)")
def test_after_percent_an_ascii_port_stops_at_a_byte_of_no_code(cnc: Any) -> None:
    await_tape(cnc, p71=1)
    with open_port(cnc, "v7") as host:
        host.write(b"%\r\nN1 X1\r\n" + encode("N2 X2\r\n", True))  # an ISO image is taken (bit 7 masked)
        until(lambda: cnc.read("program.P20") == "N 1 X 1.000\nN 2 X 2.000", "ASCII and ISO characters")
        host.write(bytes([0x89]) + b"N3 X3\r\n")  # 89: bit 7 set, odd parity: what a wrong baud rate delivers
        until(lambda: cnc.read("v7.state") == "failed", "a byte of no code")
    assert cnc.read("panel.message") == "WERTBEREICHES-UEBERLAUF"


@pytest.mark.manual("§2.6", "Wird vor dem Einlesen eines Programmes ein falscher Code gewählt, erscheint am "
                    "Bildschirm: WERTBEREICHES-UEBERLAUF (characters with a parity error before %)")
def test_a_parity_error_before_percent_ends_the_read_in(cnc: Any) -> None:
    await_tape(cnc)
    with open_port(cnc, "v7") as host:
        host.write(bytes([iso_byte(ord("T")) ^ 0x80]))
        until(lambda: cnc.read("v7.state") == "failed", "a character with a parity error")
    assert cnc.read("panel.message") == "WERTBEREICHES-UEBERLAUF"


@pytest.mark.manual("§2.6.3", "Alle vorgängig eintreffenden Zeichen werden nicht berücksichtigt (on an ASCII port: "
                    "control characters too, such as a DNC host's DC2 and DC4 for the tape)")
def test_control_characters_before_percent_on_an_ascii_port_are_ignored(cnc: Any) -> None:
    await_tape(cnc, p71=1)
    with open_port(cnc, "v7") as host:
        host.write(b"\x12\x14\x1b\x04\x00\r\n\x7fTAPE\x18" + b"%\r\nN1 X1\r\nM30\r\n")
        until(lambda: cnc.read("v7.state") in ("done", "failed"), "the read-in ends")
    assert cnc.read("v7.state") == "done" and cnc.read("panel.message") != "WERTBEREICHES-UEBERLAUF"
    assert cnc.read("program.P20") == "N 1 X 1.000"


@pytest.mark.manual("§2.6", "falsche Baud-Rate: WERTBEREICHES-UEBERLAUF (on an ASCII port: a byte with bit 7 set "
                    "and odd parity before %, which no sender set to ASCII sends)")
def test_a_byte_no_ascii_sender_sends_before_percent_ends_the_read_in(cnc: Any) -> None:
    await_tape(cnc, p71=1)
    with open_port(cnc, "v7") as host:
        host.write(b"\x00\x00\r\n\x7fTAPE\x80")  # 80H: bit 7 set, odd parity
        until(lambda: bytes_in(cnc, "v7") == 10, "the line has taken the bytes")
        until(lambda: cnc.read("v7.state") == "failed", "80H is no ASCII character")
    assert cnc.read("panel.message") == "WERTBEREICHES-UEBERLAUF"


@pytest.mark.manual("§2.6.1.1", "Die Baud-Rate gibt die Anzahl der pro Sekunde übertragenen Bits an (in real time, "
                    "without --pacing)")
def test_in_real_time_an_output_takes_its_frames_at_the_baud_rate(devsim_device) -> None:  # noqa: ANN001
    import time

    cnc = devsim_device("poselesta", {"boot_time": 0, "params": {70: 1}}, virtual=False)  # 300 baud ISO
    tape = encode("%\r\nN1X1.000\r\nM30\r\n", True)
    with serial.serial_for_url(cnc.port_url("v7"), baudrate=300, stopbits=2, timeout=5) as host:
        _output_on_v7(cnc, "N1 X1")
        started = time.monotonic()
        assert host.read(1) == tape[:1]
        first = time.monotonic() - started
        assert host.read(len(tape) - 1) == tape[1:]
        took = time.monotonic() - started
    assert first < 0.5 * len(tape) * 11 / 300
    assert took >= 0.9 * len(tape) * 11 / 300  # 19 characters of 11 bits at 300 baud: 0.70 s


class LateClock(VirtualClock):
    """Virtual time whose timers fire a millisecond after they are due, as an event loop's fire
    a little late in real time."""

    LATE = 0.001

    def call_at(self, when: float, callback: Callable[[], Any]) -> Timer:
        return super().call_at(when + self.LATE, callback)


@pytest.mark.manual("§2.6.3", "Baud-Rate: Mit Parameter P 70 wählbar ... 5 = 4800 Baud (nur POS III)")
@pytest.mark.manual("§2.6.1.1", "Die Baud-Rate gibt die Anzahl der pro Sekunde übertragenen Bits an (with timers "
                    "that fire late, as in real time: not fewer either)")
def test_an_output_keeps_its_baud_rate_when_timers_fire_late() -> None:
    """A character is due a frame after the one before was due, not after its timer fired: timed
    from the late moment, 1161 characters at 4800 baud took 3.8 s instead of 2.7 s in real time."""
    clock = LateClock()
    cnc = PoselestaDevice(clock=clock, config={"boot_time": 0, "params": {70: 5}}, nvram=NonVolatileMemory(None))
    sent: list[tuple[float, bytes]] = []
    cnc.port("v7").attach(lambda data: sent.append((clock.now(), bytes(data))))
    program = "\n".join(f"N{n} X{n}.123 Y-{n}.456" for n in range(1, 60))
    tape = encode("%\r\n" + "".join(f"N{n}X{n}.123Y-{n}.456\r\n" for n in range(1, 60)) + "M30\r\n", True)
    _output_on_v7(cnc, program)
    started = clock.now()
    clock.advance(10.0)
    assert b"".join(data for _t, data in sent) == tape
    took = sent[-1][0] - started
    frames = len(tape) * 11 / 4800  # 1161 characters of 11 bits: 2.66 s
    assert frames <= took <= frames + 2 * LateClock.LATE  # (late by a timer's lateness, not by 1161 of them)


@pytest.mark.manual("§2.6.1.2", "ISO-Code: sxxxxxxxPSS; ASCII-Code: sxxxxxxxSS (what --pacing times a character "
                    "at: 11 and 10 bits, on a port its host opens at 8N2)")
@pytest.mark.parametrize(("p71", "bits"), [(0, 11), (1, 10)], ids=["iso", "ascii"])
def test_a_character_takes_its_codes_frame_on_the_wire(cnc: Any, p71: int, bits: int) -> None:
    cnc.set("param.P71", p71)
    _output_on_v7(cnc, "N1 X1")
    settings = cnc.device.face("v7").serial_settings
    assert settings.describe() == "1200 8N2"  # what the host opens and the device reports
    assert settings.char_time() == pytest.approx(bits / 1200)  # what pacing holds each character for


# -- §2.6.2.1 the printout ------------------------------------------------------------------------
@pytest.mark.manual("§2.6.2.1", "Nach jeder ausgedruckten Funktion erfolgt CR. Es wird kein LF generiert. "
                    "Beispiel: % CR CR CR, N 1 CR, X 100.000 CR, Y 20.123 CR, G 00 CR, # CR, N 2 …")
def test_the_printout_has_one_function_a_line_as_the_manuals_example(cnc: Any) -> None:
    cnc.set("program.P03", "N1 X100 Y20.123 G00 #\nN2 Y1000 F500 M20")
    cnc.set("panel.mode", "EXTERNAL_MEDIUM")
    cnc.set("panel.program", 3)
    expected = b"%\r\r\rN 1\rX 100.000\rY 20.123\rG 00\r#\rN 2\rY 1000.000\rF 500\rM 20\rM 30\r"
    with open_port(cnc, "v6") as printer:
        cnc.set("v6.transfer", "printer")
        cnc.advance(expected.count(b"\r") * 0.83 + len(expected) * 12 / 1200)
        assert cnc.read("v6.state") == "done"
        assert printer.read(len(expected)) == expected


@pytest.mark.manual("§2.6.2.1", "Während der Datenübertragung werden RTS und DTR auf hohem Niveau gehalten")
@pytest.mark.manual("§2.6.2.1", "Die Drucker-Rückmeldung (clear to send) wird von der Steuerung ignoriert")
def test_the_printer_lines_are_high_while_printing_and_cts_is_ignored(cnc: Any) -> None:
    cnc.set("program.P03", "N1 X1")
    cnc.set("panel.mode", "EXTERNAL_MEDIUM")
    cnc.set("panel.program", 3)
    cnc.set("input.v6_cts", False)  # the printer's buffer is full
    with open_port(cnc, "v6") as printer:
        cnc.set("v6.transfer", "printer")
        assert cnc.read("output.v6_rts") is True and cnc.read("output.v6_dtr") is True
        cnc.advance(10.0)
        assert printer.read(4) == b"%\r\r\r"
    assert cnc.read("v6.state") == "done"
    assert cnc.read("output.v6_rts") is False and cnc.read("output.v6_dtr") is False


# -- §2.6.2.2 the cassette ------------------------------------------------------------------------
@pytest.mark.manual("§2.6.2.2", "Baud-Rate POS II: 300 fest programmiert (P 68 hat keinen Einfluss)")
@pytest.mark.manual("§2.6.2.2", "Baud-Rate POS III: 300/1200/4800 mittels P 68 wählbar")
@pytest.mark.parametrize(("variant", "p68", "baud"), [("II", 3, 300), ("II", 0, 300), ("II", 4, 300), ("II", 5, 300),
                                                      ("III", 1, 300), ("III", 3, 1200), ("III", 5, 4800)])
def test_the_cassette_baud_rate(devsim_device, variant: str, p68: int, baud: int) -> None:  # noqa: ANN001
    cnc = devsim_device("poselesta", {"variant": variant, "params": {68: p68}})
    cnc.set("program.P03", "N1 X1")
    cnc.set("panel.mode", "EXTERNAL_MEDIUM")
    cnc.set("panel.program", 3)
    with serial.serial_for_url(cnc.port_url("v6"), baudrate=baud, stopbits=2, timeout=5) as recorder:
        cnc.set("v6.transfer", "cassette_out")
        assert cnc.runtime.line_status(cnc.name, "v6")["device"]["baudrate"] == baud
        cnc.advance(13.0 + 1.5 * 11 / baud)  # the leader, then one ISO character
        assert bytes_out(cnc, "v6") == 1
        assert recorder.read(1) == encode("%", True)


@pytest.mark.manual("§2.6.2.2", "Die Ansteuerung erfolgt mit den Signalen RTS und DTR (Ausgabe auf Band: Mode 2)")
def test_the_cassette_records_with_rts_and_dtr_high(cnc: Any) -> None:
    cnc.set("program.P03", "N1 X1")
    cnc.set("panel.mode", "EXTERNAL_MEDIUM")
    cnc.set("panel.program", 3)
    cnc.set("v6.transfer", "cassette_out")
    assert cnc.read("output.v6_dtr") is True and cnc.read("output.v6_rts") is True
    cnc.advance(12.9)
    assert bytes_out(cnc, "v6") == 0  # the leader: nothing is sent for ca. 13 s
    cnc.set("v6.transfer", "idle")
    assert cnc.read("output.v6_dtr") is False and cnc.read("output.v6_rts") is False


# -- §2.6.2.3 tape reader / punch, TTY --------------------------------------------------------------
@pytest.mark.manual("§2.6.2.3", "Baud-Rate mit Parameter P 68 wählbar: 4 = 2400 Baud, 5 = 4800 Baud nur bei POS III möglich")
@pytest.mark.parametrize("p68", [4, 5])
def test_pos_ii_has_no_2400_or_4800_baud_on_v6(devsim_device, p68: int) -> None:  # noqa: ANN001
    cnc = devsim_device("poselesta", {"variant": "II", "params": {68: p68}})
    cnc.set("program.P03", "N1 X1")
    cnc.set("panel.mode", "EXTERNAL_MEDIUM")
    cnc.set("panel.program", 3)
    with pytest.raises(ValueError, match="not available on POS II"):
        cnc.set("v6.transfer", "output")
    assert cnc.read("panel.message") == "WERTBEREICHES-UEBERLAUF"


@pytest.mark.manual("§2.6.2.3", "Baud-Rate mit Parameter P 68 wählbar: 0 = 110 … 5 = 4800 Baud")
@pytest.mark.manual("§2.6.2.3", "Code: P 69 = 0 sxxxxxxxPSS (ISO), P 69 = 1 sxxxxxxxSS (ASCII)")
@pytest.mark.parametrize(("p68", "p69", "baud"), [(0, 0, 110), (2, 1, 600), (4, 0, 2400)])
def test_the_punch_runs_at_p68_in_the_code_of_p69(cnc: Any, p68: int, p69: int, baud: int) -> None:
    cnc.set("param.P68", p68)
    cnc.set("param.P69", p69)
    cnc.set("program.P03", "N1 X1")
    cnc.set("panel.mode", "EXTERNAL_MEDIUM")
    cnc.set("panel.program", 3)
    bits = 11 if p69 == 0 else 10
    with serial.serial_for_url(cnc.port_url("v6"), baudrate=baud, stopbits=2, timeout=5) as punch:
        cnc.set("v6.transfer", "output")
        cnc.advance(3.5 * bits / baud)
        assert bytes_out(cnc, "v6") == 3
        assert punch.read(3) == encode("%\r\n", p69 == 0)


# -- §2.6.3 the DNC protocol, through the V7 pty -------------------------------------------------------
def _read_in(cnc: Any, text: bytes) -> None:
    cnc.set("param.P71", 1)  # ASCII, so the tapes below read as text
    await_tape(cnc)
    with open_port(cnc, "v7") as host:
        host.write(text)
        until(lambda: bytes_in(cnc, "v7") == len(text), "the line has taken the tape")


@pytest.mark.manual("§2.6.3", "Die Satznummer muss mit Nxxx vorgewählt werden. Die Eingabe N 01 und N 1 ist möglich.")
@pytest.mark.manual("§2.6.3", "Leerzeichen zwischen einzelnen Funktionen müssen nicht eingegeben werden")
@pytest.mark.manual("§2.6.3", "Führende oder nach dem Komma folgende Nullen müssen nicht eingegeben werden")
@pytest.mark.manual("§2.6.3", "Die NC-Sätze müssen mit CR abgeschlossen werden. LF kann, muss jedoch nicht, "
                    "eingegeben werden.")
@pytest.mark.manual("§2.6.3", "Die Reihenfolge der zu programmierenden Funktionen ist beliebig")
def test_dnc_read_in_takes_the_protocols_liberties(cnc: Any) -> None:
    _read_in(cnc, b"%\r\nN 01 X 0010.500 Y-3\r\nN2Y.25X0\rN 3 F 0500 G 01\r\nM30\r\n")
    until(lambda: cnc.read("v7.state") == "done", "M30 ends the read-in")
    assert cnc.read("program.P20") == "N 1 X 10.500 Y- 3.000\nN 2 X 0.000 Y 0.250\nN 3 F 500 G 01"


@pytest.mark.manual("§2.6.3", "Löschzeichen (delete) werden überlesen")
@pytest.mark.manual("§2.6.3", "Falsche oder nicht definierte Zeichen werden überlesen")
@pytest.mark.manual("§2.6.3", "Mit C kann ein falscher Wert einer noch nicht abgeschlossenen Funktion gelöscht und "
                    "neu eingegeben werden")
@pytest.mark.manual("§2.6.3", "Die Satzunterdrückung # muss gegebenenfalls im aktuellen Satz stehen")
def test_dnc_read_in_skips_delete_and_undefined_characters(cnc: Any) -> None:
    _read_in(cnc, b"%\r\nN1 X1\x7f2 ?y\r\nN2 X7C8 #\r\nM30\r\n")
    until(lambda: cnc.read("v7.state") == "done", "M30 ends the read-in")
    assert cnc.read("program.P20") == "N 1 X 12.000\nN 2 X 8.000 #"


@pytest.mark.manual("§2.6.3", "Die Datenein- und Ausgabe wird mit M 02 nicht unterbrochen, sondern erst mit M 30")
@pytest.mark.manual("§2.6.3", "beim Einlesen in die Steuerung kann M 30 mit oder ohne Satznummer eingegeben werden")
@pytest.mark.parametrize("end", [b"M30\r", b"N9 M30\r"])
def test_dnc_read_in_ends_at_m30_not_m02(cnc: Any, end: bytes) -> None:
    _read_in(cnc, b"%\rN1 X1 M02\r")
    assert cnc.read("v7.state") == "receiving"
    with open_port(cnc, "v7") as host:
        host.write(b"N2 X2\r" + end + b"N3 X3\r")
        until(lambda: cnc.read("v7.state") == "done", "M30 ends the read-in")
    assert cnc.read("program.P20") == "N 1 X 1.000 M 02\nN 2 X 2.000"


@pytest.mark.manual("§2.6.3", "In einem Satz können maximal folgende Funktionen eingegeben werden: 2 Koordinaten, "
                    "2 Hilfskoordinaten, 4 G-Funktionen, 2 M-Funktionen")
@pytest.mark.parametrize("block", [b"N2 X1 Y1 Z1", b"N2 I1 J1 K1", b"N2 G01 G90 G40 G17 G04", b"N2 M03 M08 M10"])
def test_dnc_read_in_refuses_a_block_beyond_the_block_format(cnc: Any, block: bytes) -> None:
    _read_in(cnc, b"%\rN1 X1\r" + block + b"\rM30\r")
    until(lambda: cnc.read("v7.state") == "failed", "the block format is exceeded")
    assert cnc.read("panel.message") == "WERTBEREICHES-UEBERLAUF"
    assert cnc.read("program.P20") == "N 1 X 1.000"


@pytest.mark.manual("§2.6.3", "In einem Satz können maximal folgende Funktionen eingegeben werden: 2 Koordinaten, "
                    "2 Hilfskoordinaten, 4 G-Funktionen, 2 M-Funktionen")
def test_dnc_read_in_takes_a_block_at_the_block_format(cnc: Any) -> None:
    """The most one block may hold (§2.6.3; spec §3.4): taken whole, through the V7 pty."""
    _read_in(cnc, b"%\rN1 X1 Y2 I3 J4 G01 G90 G40 G17 M03 M08 F100 S200 T01 L1.5\rM30\r")
    until(lambda: cnc.read("v7.state") == "done", "M30 ends the read-in")
    program = cnc.read("program.P20")
    assert program.startswith("N 1 ") and all(word in program for word in ("G 01", "G 17", "M 03", "M 08"))
    assert cnc.read("panel.message") != "WERTBEREICHES-UEBERLAUF"


# -- §2.6.4 the external keyboard V8 -----------------------------------------------------------------
@pytest.mark.manual("§2.6.4", "Baud-Rate: 1200 fest programmiert")
@pytest.mark.manual("§2.6", "V 8 (externe Tastatur) kann in jeder Betriebsart angewählt werden")
@pytest.mark.parametrize("mode", ["MANUAL", "EXTERNAL_OPERATION", "AUTO_CONTINUOUS"])
def test_the_keyboard_port_runs_at_1200_baud_in_every_mode(cnc: Any, mode: str) -> None:
    cnc.set("param.P68", 0)
    cnc.set("param.P70", 5)
    cnc.set("panel.mode", mode)
    cnc.set("input.keyboard_external", True)
    cnc.advance(0.1)
    assert cnc.runtime.line_status(cnc.name, "v8")["device"]["baudrate"] == 1200
    with open_port(cnc, "v8") as keyboard:
        keyboard.write(encode("H", True))  # key P
        until(lambda: cnc.read("keyboard.accepted") == 1, "the key is taken")
    assert cnc.read("keyboard.last_key") == 0x48


@pytest.mark.manual("§2.4.9", "Ueber den Parameter P 67 kann der Summer abgeschaltet werden")
@pytest.mark.parametrize(("p67", "buzzes"), [(0, True), (1, False)])
def test_p67_switches_the_buzzer_off(cnc: Any, p67: int, buzzes: bool) -> None:
    cnc.set("param.P67", p67)
    cnc.set("input.keyboard_external", True)
    cnc.advance(0.1)
    with open_port(cnc, "v8") as keyboard:
        keyboard.write(encode("H", True))
        until(lambda: cnc.read("keyboard.accepted") == 1, "the key is taken")
    assert cnc.read("output.buzzer") is buzzes


@pytest.mark.manual("§2.6.1.1", "Jedes Zeichen beginnt mit einem Start-Bit und endet mit Stop-Bits; es können auch "
                    "mehrere Stop-Bits nacheinander eintreffen (pauses between characters)")
def test_a_read_in_takes_pauses_between_characters(cnc: Any) -> None:
    await_tape(cnc)
    tape = encode("%\rN1 X1\rM30\r", True)
    with open_port(cnc, "v7") as host:
        for k in range(len(tape)):
            host.write(tape[k:k + 1])
            until(lambda k=k: bytes_in(cnc, "v7") == k + 1, "the line has taken the character")
            cnc.advance(0.5)  # a long idle line (stop level) between characters
    assert cnc.read("v7.state") == "done" and cnc.read("program.P20") == "N 1 X 1.000"


@pytest.mark.manual("§2.6.3", "Das ELESTA-Kassettengerät kann nur am Stecker V 6 angeschlossen werden")
def test_the_cassette_functions_are_on_v6_only(cnc: Any) -> None:
    cnc.set("panel.mode", "EXTERNAL_OPERATION")
    for name in ("cassette_out", "cassette_in", "printer"):
        with pytest.raises(ValueError):
            cnc.set("v7.transfer", name)
    assert cnc.read("v7.transfer") == "idle"


@pytest.mark.manual("§2.6.2.2", "Der Parameterkatalog kann beim POS II nur mit dem ISO-Code auf Band aufgenommen "
                    "werden, weil bei der Wiedergabe vom Band der Parameterkatalog inkl. P 69 GELOESCHT wird")
def test_pos_ii_plays_the_catalogue_back_in_iso_only(devsim_device) -> None:  # noqa: ANN001
    cnc = devsim_device("poselesta", {"variant": "II", "params": {69: 1}})  # V6 in ASCII
    cnc.set("panel.mode", "EXTERNAL_MEDIUM")
    cnc.set("panel.program", 99)
    for iso, state in ((False, "failed"), (True, "done")):
        cnc.set("v6.transfer", "cassette_in")
        assert cnc.read("param.P69") == 0  # cleared: the tape is read in ISO
        cnc.advance(13.0)
        with serial.serial_for_url(cnc.port_url("v6"), baudrate=300, stopbits=2, timeout=5) as recorder:
            recorder.write(encode("%\rN70P3\rM30\r", iso))
            until(lambda state=state: cnc.read("v6.state") == state, f"the {'ISO' if iso else 'ASCII'} tape")
    assert cnc.read("param.P70") == 3


@pytest.mark.manual("§2.6.2.2", "Baud-Rate POS III: 300/1200/4800 mittels P 68 wählbar")
@pytest.mark.manual("§2.6.2.2", "Der Parameterkatalog kann beim POS II nur mit dem ISO-Code auf Band aufgenommen werden "
                    "... Diese Einschränkung gilt beim POS III nicht")
@pytest.mark.parametrize("p68", [4, 5])  # the cassette at 300 and at 4800 baud
def test_pos_iii_plays_back_the_catalogue_it_recorded_at_its_cassette_rate(devsim_device, p68: int) -> None:  # noqa: ANN001
    """The limit of 1200 baud for reading the catalogue is that of the tape reader and of the DNC
    port (§2.6.2.3, §2.6.3); the cassette section names none for POS III: what T2 recorded, T3
    plays back (it was refused by P68's number: at P68 = 4 the cassette runs at 300 baud)."""
    cnc = devsim_device("poselesta", {"v6_peer": "cassette", "params": {68: p68, 44: 5000}})
    cnc.set("panel.mode", "EXTERNAL_MEDIUM")
    cnc.set("panel.program", 99)
    cnc.set("v6.transfer", "cassette_out")
    cnc.advance(13.0 + 120.0)  # the leader, then about 1500 characters at 300 baud
    assert cnc.read("v6.state") == "done"
    cnc.set("param.P44", 4000)
    cnc.set("v6.transfer", "cassette_in")  # (the key switch is open)
    cnc.advance(13.0 + 1.0)
    assert cnc.read("v6.state") == "done" and cnc.read("panel.message") == ""
    assert cnc.read("param.P44") == 5000 and cnc.read("param.P68") == p68


@pytest.mark.manual("§2.6.2.3", "Beispiel: the manual's listing (N 1 … N 115, M 30) is a tape the reader takes (the "
                    "lost % restored)")
@pytest.mark.manual("§2.6.2.3", "Das Einlese-Protokoll kann jedoch ohne die Leerzeichen eingegeben werden "
                    "(and with them, as the listing shows)")
def test_the_manuals_example_listing_reads_in_through_v6(cnc: Any) -> None:
    from tests.poselesta.test_tape import LISTING

    cnc.set("panel.mode", "EXTERNAL_MEDIUM")
    cnc.set("panel.program", 7)
    cnc.set("v6.transfer", "input")
    with open_port(cnc, "v6") as reader:
        reader.write(encode(LISTING.replace("\n", "\r\n"), True))
        until(lambda: cnc.read("v6.state") == "done", "M 30 ends the tape")
    lines = cnc.read("program.P07").splitlines()
    assert len(lines) == 22
    assert lines[0] == "N 1 X 0.000 Y 43.144 F 1002" and lines[5] == "N 6 X 0.000 Z 1.000 G 40 M 02"
    assert lines[-1] == "N 115 G 11"
