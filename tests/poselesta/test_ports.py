"""The POSELESTA's three ports through real ptys, as a DNC program, a tape reader or punch
emulator and a keyboard emulator use them (spec §3.2, §3.5–§3.8, §3.10; vectors §6.7–§6.9)."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import pytest
import serial

from devsim.devices.poselesta.codes import encode

R1 = bytes.fromhex("00000000 A58D0A 4EB1D8B1302E35592D338D0A 4EB2A0473030A0D830A05930A04D30B28D0A 4D33308D0A")
O1 = bytes.fromhex(
    "25 0D 0A 4E 31 58 31 30 2E 35 30 30 59 2D 33 2E 30 30 30 0D 0A"
    "4E 32 58 30 2E 30 30 30 59 30 2E 30 30 30 47 30 30 4D 30 32 0D 0A 4D 33 30 0D 0A"
)


def until(check: Callable[[], Any], what: str) -> None:
    """Wait for the runtime thread to have handled the host's bytes (a real pty, no sleeps)."""
    deadline = time.monotonic() + 10
    while not check():
        assert time.monotonic() < deadline, what


@pytest.fixture
def cnc(devsim_device):  # noqa: ANN001, ANN201
    return devsim_device("poselesta", {"input_rise_ms": 0, "input_fall_ms": 0})  # (§2.3's delay: test_manual_inputs)


def open_port(cnc: Any, port: str) -> serial.Serial:
    return serial.serial_for_url(cnc.port_url(port), baudrate=1200, stopbits=2, timeout=5)


@pytest.mark.manual("§2.4.5", "nach ca. 2 Sekunden schaltet die Steuerung auf Handbetrieb und NC-Bereitschaft auf H-Level")
def test_boot_gives_manual_mode_and_nc_ready(cnc: Any) -> None:
    assert cnc.read("panel.mode") == "MANUAL"
    assert cnc.read("output.nc_ready") is True and cnc.read("output.data_bus") == 0x08


@pytest.mark.manual("§2.6.3", "Die Programmnummer Pxx (z. B. P 20) wird nicht übertragen")
@pytest.mark.manual("§2.6.3", "Ein Drucker-Anschluss ist nicht sinnvoll, da die Daten nicht formatiert ausgegeben werden")
@pytest.mark.manual("§2.6.3", "Bei einem Ausdruck wird M 30 automatisch generiert")
def test_dnc_read_in_r1_then_output_o1(cnc: Any) -> None:
    cnc.set("panel.mode", "EXTERNAL_OPERATION")
    assert cnc.read("output.data_bus") == 0x0A
    cnc.set("panel.program", 20)
    cnc.set("v7.transfer", "input")
    with open_port(cnc, "v7") as host:
        host.write(R1)
        until(lambda: cnc.read("v7.state") == "done", "the read-in ends with M30")
        assert cnc.read("program.P20") == "N 1 X 10.500 Y- 3.000\nN 2 X 0.000 Y 0.000 G 00 M 02"
        assert host.in_waiting == 0  # nothing answered (spec §3.5.5)
        cnc.set("param.P71", 1)  # ASCII
        cnc.set("v7.transfer", "output")
        cnc.advance(len(O1) * 10 / 1200)  # ASCII: 10 bits a character (§2.6.1.2)
        assert host.read(len(O1)) == O1  # O1: unformatted, CR LF, generated M30
        assert cnc.read("v7.transfer") == "idle" and cnc.read("v7.state") == "done"


@pytest.mark.manual("§2.6", "Beim Einlesen eines neuen Programmes wird zuerst das vorgewählte Programm (Pxx) gelöscht")
@pytest.mark.manual("§2.6", "Wird vor dem Einlesen eines Programmes ein falscher Code gewählt, erscheint am Bildschirm: WERTBEREICHES-UEBERLAUF")
def test_the_selected_program_is_deleted_first_and_a_wrong_code_stops(cnc: Any) -> None:
    cnc.set("program.P20", "N1 X5\nN2 Y6")
    cnc.set("panel.mode", "EXTERNAL_OPERATION")
    cnc.set("panel.program", 20)
    cnc.set("v7.transfer", "input")
    assert cnc.read("program.P20") == ""  # deleted at the start (manual §2.6)
    with open_port(cnc, "v7") as host:
        host.write(bytes.fromhex("25 0D 0A 4E 31 58 31 0D 0A"))  # R14: ASCII into ISO
        until(lambda: cnc.read("v7.state") == "failed", "the parity error stops the read-in")
    assert cnc.read("panel.message") == "WERTBEREICHES-UEBERLAUF"
    assert cnc.read("programs") == []
    cnc.set("panel.clear_message", True)
    assert cnc.read("panel.message") == ""


@pytest.mark.manual("§2.6", "V 7 in der Betriebsart EXT, V 6 in der Betriebsart Σ")
def test_transfers_need_their_mode_and_input_while_idle_is_discarded(cnc: Any) -> None:
    with pytest.raises(ValueError, match="needs mode EXTERNAL_OPERATION"):
        cnc.set("v7.transfer", "input")
    with open_port(cnc, "v6") as host:
        host.write(b"%\r\nN1 X1\r\n")
        until(lambda: cnc.read("v6.discarded") == 10, "bytes on an idle port are counted and dropped")
    cnc.set("panel.mode", "EXTERNAL_MEDIUM")
    cnc.set("v6.transfer", "input")
    with pytest.raises(ValueError, match="busy"):
        cnc.set("v6.transfer", "output")
    cnc.set("v6.transfer", "idle")
    assert cnc.read("v6.state") == "cancelled"
    cnc.set("v6.transfer", "input")
    cnc.set("panel.mode", "MANUAL")  # spec §3.5.1: a mode change cancels the transfer
    assert cnc.read("v6.state") == "cancelled"
    with open_port(cnc, "v6") as host:
        tape, before = b"%\r\nN1 X1\r\nM30\r\n", cnc.read("v6.discarded")
        host.write(tape)
        until(lambda: cnc.read("v6.discarded") == before + len(tape), "the port is idle again: its bytes are dropped")
    assert cnc.read("programs") == []


def test_bytes_from_the_host_during_an_output_are_counted_as_discarded(cnc: Any) -> None:
    """Spec §2.6: bytes arriving while no input function is active are discarded and counted;
    ``v7.discarded`` is "bytes received while no input transfer ran", and an output is none."""
    cnc.set("program.P20", "N1 X1\nN2 X2\nN3 X3")
    cnc.set("panel.mode", "EXTERNAL_OPERATION")
    cnc.set("panel.program", 20)
    cnc.set("v7.transfer", "output")
    with open_port(cnc, "v7") as host:
        tape = b"%\r\nN9 X9\r\nM30\r\n"  # a host answering with a tape: no input transfer runs
        host.write(tape)
        until(lambda: cnc.read("v7.discarded") == len(tape), "the bytes are counted and dropped")
        assert cnc.read("v7.state") == "sending"
        cnc.advance(1.0)
        assert cnc.read("v7.state") == "done"
    assert cnc.read("program.P20") == "N 1 X 1.000\nN 2 X 2.000\nN 3 X 3.000"


@pytest.mark.manual("§2.6.2.3", "Die Daten werden formatiert ausgegeben, d.h. die Abstände zwischen den einzelnen Funktionen werden mit Leerzeichen ausgefüllt")
@pytest.mark.manual("§2.6.2.3", "Beim Einlesen wird zuerst das in der Steuerung vorgewählte Programm gelöscht")
def test_tape_punch_output_is_formatted_and_reads_back(cnc: Any) -> None:
    cnc.set("program.P07", "N1 X0 Y-43.144 F1002\nN2 X-20 F750 G42\nN5 X5 #")
    cnc.set("panel.mode", "EXTERNAL_MEDIUM")
    cnc.set("panel.program", 7)
    with open_port(cnc, "v6") as punch:  # (the punch is on before the operator starts)
        cnc.set("v6.transfer", "output")
        assert cnc.read("output.v6_rts") is True and cnc.read("output.v6_dtr") is True
        cnc.advance(5)
        tape = punch.read_until(encode("M 30\r\n", iso=True))
    assert tape == encode("%\r\nN 1 X 0.000 Y- 43.144 F 1002\r\nN 2 X- 20.000 F 750 G 42\r\nN 5 X 5.000 #\r\n"
                          "M 30\r\n", iso=True)
    cnc.advance(5)
    assert cnc.read("output.v6_rts") is False
    cnc.set("panel.program", 8)
    cnc.set("v6.transfer", "input")
    with open_port(cnc, "v6") as reader:
        reader.write(tape)
        until(lambda: cnc.read("v6.state") == "done", "the punched tape reads back")
    assert cnc.read("program.P08") == cnc.read("program.P07")


@pytest.mark.manual("§2.6.2.2", "Da der Beginn der aktiven Schicht nicht automatisch erkannt wird, ist eine Vorlaufzeit von ca. 13 Sekunden fest programmiert")
@pytest.mark.manual("§2.6.2.1", "Die Datenausgabe beim Drucker wird nach jedem CR für ca. 820 ms (Wagenrücklauf) angehalten")
@pytest.mark.manual("§2.6.2.1", "Nach jeder ausgedruckten Funktion erfolgt CR. Es wird kein LF generiert (% CR CR CR)")
def test_cassette_leader_and_printer_pauses_run_on_the_device_clock(cnc: Any) -> None:
    cnc.set("panel.mode", "EXTERNAL_MEDIUM")
    cnc.set("panel.program", 3)
    cnc.set("v6.transfer", "cassette_in")
    assert cnc.read("v6.state") == "leader" and cnc.read("output.v6_rts") is False
    with open_port(cnc, "v6") as recorder:
        tape = encode("%\rN1 X1\rM30\r", iso=True)
        recorder.write(tape)  # within the 13 s leader: lost
        until(lambda: _bytes_in(cnc, "v6") == len(tape), "the line has taken the bytes")
        cnc.advance(13.0)
        assert cnc.read("v6.state") == "wait_start"
        recorder.write(tape)
        until(lambda: cnc.read("v6.state") == "done", "read after the leader")
    assert cnc.read("program.P03") == "N 1 X 1.000"
    with open_port(cnc, "v6") as printer:
        cnc.set("v6.transfer", "printer")
        cnc.advance(0.021)  # "%" CR at 1200 baud, 12 bits (P69 = 0): 20 ms
        assert printer.read(2) == b"%\r"
        assert printer.in_waiting == 0  # 820 ms after every CR (§2.6.2.1)
        cnc.advance(0.818)  # the 820 ms, then the next CR's 10 ms
        assert printer.in_waiting == 0
        cnc.advance(0.002 + 0.010)
        assert printer.read(1) == b"\r"
        cnc.advance(0.83)  # 820 ms and one CR's 10 ms
        assert printer.read(1) == b"\r"
        cnc.advance(0.86)  # 820 ms and "N 1" CR: 40 ms
        assert printer.read(4) == b"N 1\r"


def _bytes_in(cnc: Any, port: str) -> int:
    return int(cnc.runtime.line_status(cnc.name, port)["bytes_in"])


@pytest.mark.manual("§2.6.4", "Zwischen den einzelnen gesendeten Zeichen muss eine Pause von mindestens 100ms eingehalten werden, um einen Ueberlauf des Eingabepuffers zu vermeiden")
@pytest.mark.manual("§2.6.4", "Ueber die Eingangsklemme V21/9 kann von der internen auf die externe Tastatur umgeschaltet werden")
@pytest.mark.manual("§2.6.4", "Die Taste P hat z. B. den Code 48 (ISO-Code H)")
@pytest.mark.manual("§2.4.9", "Bei Anschluss eines Summers zeigt ein kurzes akustisches Signal, dass die Steuerung die Eingabe angenommen hat")
def test_keyboard_codes_buffer_and_overflow(cnc: Any) -> None:
    """Spec §6.9 K1, K3–K7 on the V8 pty, with the 100 ms per key on the device clock."""
    with open_port(cnc, "v8") as keys:
        keys.write(b"\x48")  # K7: the internal keyboard is selected
        until(lambda: _bytes_in(cnc, "v8") == 1, "the line has taken the byte")
        assert cnc.read("keyboard.accepted") == 0
        cnc.set("input.keyboard_external", True)
        keys.write(b"\x48")  # K1
        until(lambda: cnc.read("keyboard.accepted") == 1, "key P accepted")
        assert cnc.read("keyboard.last_key") == 0x48 and cnc.read("output.buzzer") is True
        cnc.advance(0.15)
        keys.write(b"\x48")  # K3: 150 ms later, accepted too
        until(lambda: cnc.read("keyboard.accepted") == 2, "second key")
        cnc.advance(0.15)
        keys.write(b"\x48\x48\x48")  # K4: the third is lost
        until(lambda: cnc.read("keyboard.lost") == 1, "overflow")
        assert cnc.read("keyboard.accepted") == 3
        cnc.advance(0.1)
        assert cnc.read("keyboard.accepted") == 4  # the buffered one
        keys.write(b"\xc8\x81")  # K5 wrong parity, K6 no key code
        until(lambda: _bytes_in(cnc, "v8") == 8, "the line has taken the bytes")
        cnc.advance(0.2)
        assert cnc.read("keyboard.accepted") == 4
        assert keys.in_waiting == 0  # V8 never answers
    events = {name for _, name in cnc.device.model.events}  # (spec §3.10: each dropped key is an event)
    assert {"v8.v8_ignored_internal_selected", "v8.v8_overflow", "v8.v8_parity_error", "v8.v8_unknown_code"} <= events


def test_programs_survive_a_power_cycle(cnc: Any) -> None:
    cnc.set("program.P12", "N10 G01 X1 F100\nN20 M30")
    cnc.power_cycle()
    assert cnc.read("programs") == [12]
    assert cnc.read("program.P12") == "N 10 X 1.000 F 100 G 01"  # (an M30 block ends the entry)


@pytest.mark.manual("§2.6", "Stecker V6 und V7: Ein- und Ausgabe der NC-Programme oder auch der Maschinenparameter")
@pytest.mark.manual("§2.6.3", "Bei POS III sind Baudraten bis 1200 sowie ISO- & ASCII-Code möglich (Parameterkatalog)")
def test_the_parameter_catalogue_p99_goes_out_and_comes_back_in(cnc: Any) -> None:
    """Spec §3.9 (S13): P99 through T6/T7 as blocks N<number> P<value>; on POS III the read-in
    clears the catalogue first and keeps the line of its start; the values act after M30."""
    cnc.set("param.P71", 1)  # ASCII on V7
    cnc.set("param.P44", 5000)
    cnc.set("panel.mode", "EXTERNAL_OPERATION")
    cnc.set("panel.program", 99)
    with open_port(cnc, "v7") as host:
        cnc.set("v7.transfer", "output")
        cnc.advance(20.0)  # the catalogue leaves at 1200 baud (device time)
        tape = host.read_until(b"M30\r\n")
    lines = tape.decode("ascii").split("\r\n")
    assert lines[:3] == ["%", "N1P0", "N2P0"] and lines[-2:] == ["M30", ""]
    assert "N44P5000" in lines and "N70P3" in lines and "N72P20" in lines and not any(x.startswith("N79") for x in lines)
    # the software limits (mm) keep their decimals, "as the parameter's unit requires" (N9 P250.000)
    assert "N9P99999.000" in lines and "N16P-99999.000" in lines
    assert len(lines) == 1 + 97 + 2
    cnc.set("v7.transfer", "input")
    assert cnc.read("param.P44") == 0 and cnc.read("param.P71") == 0  # cleared at the start
    with open_port(cnc, "v7") as host:
        host.write(b"%\r\nN9P250.000\r\nN44P4500\r\nN70P3\r\nN71P1\r\nN72P30\r\nN97P-12.5\r\nM30\r\n")
        until(lambda: cnc.read("v7.state") == "done", "the catalogue is read")  # (still ASCII 1200)
    assert [cnc.read(f"param.P{n}") for n in (9, 44, 70, 71, 72, 97, 48)] == [250, 4500, 3, 1, 30, -12.5, 0]


@pytest.mark.manual("§2.6.3", "Das Einlesen des Parameterkatalogs ist bei POS II nur im ISO-Code mit 110 Baud möglich, "
                    "da vor dem Einlesen der gesamte Parameterkatalog (inkl. P 70 und P 71) GELOESCHT wird")
@pytest.mark.manual("§2.6", "Wird vor dem Einlesen eines Programmes eine falsche Baud-Rate gewählt: "
                    "WERTBEREICHES-UEBERLAUF")
def test_pos_ii_reads_the_catalogue_only_at_110_baud_iso(devsim_device) -> None:  # noqa: ANN001
    """Spec §3.9 (S12): POS II clears the whole catalogue, P70/P71 included, at the start, so the
    rest must come at 110 baud ISO: at 1200 baud the control sees garbage, never a ``%``, and
    the read-in ends with WERTBEREICHES-UEBERLAUF (manual §2.6: a wrong baud rate), nothing read."""
    cnc = devsim_device("poselesta", {"variant": "II"})
    cnc.set("panel.mode", "EXTERNAL_OPERATION")
    cnc.set("panel.program", 99)
    cnc.set("v7.transfer", "input")
    assert cnc.read("param.P70") == 0 and cnc.read("param.P72") == 0
    tape = encode("%\r\nN70P3\r\nN72P20\r\nM30\r\n", True)
    with serial.serial_for_url(cnc.port_url("v7"), baudrate=1200, stopbits=2, timeout=5) as host:
        host.write(tape)
        until(lambda: cnc.runtime.line_status(cnc.name, "v7")["bytes_in"] >= len(tape), "the bytes arrive")
        until(lambda: cnc.read("v7.state") == "failed", "the garbled tape stops the read-in")
    assert cnc.read("panel.message") == "WERTBEREICHES-UEBERLAUF" and cnc.read("param.P70") == 0
    cnc.set("v7.transfer", "input")
    with serial.serial_for_url(cnc.port_url("v7"), baudrate=110, stopbits=2, timeout=5) as host:
        host.write(tape)
        until(lambda: cnc.read("v7.state") == "done", "110 baud ISO is read")
    assert cnc.read("param.P70") == 3 and cnc.read("param.P72") == 20


def test_a_locked_key_switch_refuses_the_catalogue(cnc: Any) -> None:
    cnc.set("input.key_switch", False)
    cnc.set("panel.mode", "EXTERNAL_OPERATION")
    cnc.set("panel.program", 99)
    with pytest.raises(Exception, match="key switch"):
        cnc.set("v7.transfer", "input")
    assert cnc.read("param.P70") == 3


def test_a_locked_key_switch_refuses_a_parameter_entered_at_the_panel(cnc: Any) -> None:
    """Spec §4.5 (V21/8, manual §2.3.10 lost): with the key switch locked the machine parameters
    cannot be changed, by the keyboard as little as by a read-in; unlocked, the entry is taken."""
    cnc.set("input.key_switch", False)
    with pytest.raises(Exception, match="key switch"):
        cnc.set("param.P72", 50)
    assert cnc.read("param.P72") == 20
    assert "key_switch_locked" in [name for _, name in cnc.device.model.events]
    cnc.set("input.key_switch", True)
    cnc.set("param.P72", 50)
    assert cnc.read("param.P72") == 50


@pytest.mark.manual("§2.3.21", "Programme lassen sich schützen und freigeben. Das Freigeben ist nur in Stellung offen möglich")
def test_a_protected_program_is_not_overwritten_by_a_read_in(cnc: Any) -> None:
    """S32 (§2.3.21, spec §4.5 G-LOCK): protect P20; with the program lock closed (V22/9 L) it
    cannot be released, a read-in into it is refused before anything is deleted; opened, it can."""
    cnc.set("program.P20", "N1 X1")
    cnc.set("panel.protect", 20)
    cnc.set("input.program_lock_open", False)
    cnc.set("panel.mode", "EXTERNAL_OPERATION")
    cnc.set("panel.program", 20)
    with pytest.raises(Exception, match="protected"):
        cnc.set("v7.transfer", "input")
    with pytest.raises(Exception, match="program lock open"):
        cnc.set("panel.release", 20)
    assert cnc.read("program.P20") == "N 1 X 1.000" and cnc.read("protected") == [20]
    cnc.set("input.program_lock_open", True)
    cnc.set("panel.release", 20)
    cnc.set("v7.transfer", "input")
    assert cnc.read("program.P20") == ""  # read-in deletes the pre-selected program first


@pytest.mark.manual("§2.6.2.3", "Beim POS III ist das Einlesen der Parameter mit Baud-Raten bis 1200 Baud im ISO- oder ASCII-Code möglich")
def test_pos_iii_reads_the_catalogue_at_1200_baud_at_most(cnc: Any) -> None:
    """Spec §3.9: P70 = 5 (4800 baud) refuses the catalogue read-in, nothing is cleared."""
    cnc.set("param.P70", 5)
    cnc.set("panel.mode", "EXTERNAL_OPERATION")
    cnc.set("panel.program", 99)
    with pytest.raises(Exception, match="1200 baud"):
        cnc.set("v7.transfer", "input")
    assert cnc.read("panel.message") == "WERTBEREICHES-UEBERLAUF" and cnc.read("param.P70") == 5


@pytest.mark.manual("§2.6.4", "Der angezeigte Code ist um 1 höher als der tatsächlich übertragene Code: für die Taste P wird die Zahl 49 angezeigt")
@pytest.mark.manual("§2.6.4", "2D bewirkt den Abbruch vom Testprogramm N 3")
def test_the_keyboard_test_shows_each_code_plus_one(cnc: Any) -> None:
    """Vector K2 (§2.6.4): key P (48) during P79 N3 shows 49; key 2D ends the test."""
    cnc.set("input.keyboard_external", True)
    cnc.set("panel.mode", "PROGRAM_ENTRY")
    cnc.set("diagnostics.keyboard_test", "true")
    with open_port(cnc, "v8") as keyboard:
        keyboard.write(encode("H", True))
        until(lambda: cnc.read("keyboard.accepted") == 1, "the key is taken")
        assert cnc.read("diagnostics.keyboard_test") == "49"
        cnc.advance(0.2)
        keyboard.write(bytes([0x2D]))
        until(lambda: cnc.read("keyboard.accepted") == 2, "the exit key is taken")
    assert cnc.read("diagnostics.keyboard_test") == ""


def test_a_tape_sent_with_stty_and_cat_as_the_readme_shows(cnc: Any, tmp_path: Any) -> None:
    """The shell recipe of its guide (docs/kinds/poselesta.md) with tools nobody on this project wrote: coreutils `stty` sets
    the pty to 1200 baud, 8 bits, 2 stop bits, raw; `cat` writes an ASCII tape file into it."""
    import shutil
    import subprocess

    assert shutil.which("stty") and shutil.which("cat")
    cnc.set("param.P71", 1)
    cnc.set("panel.mode", "EXTERNAL_OPERATION")
    cnc.set("panel.program", 20)
    cnc.set("v7.transfer", "input")
    tape = tmp_path / "p20.txt"
    tape.write_bytes(b"%\r\nN1 X10.5 Y-3\r\nN2 G00 X0 Y0 M02\r\nM30\r\n")
    path = cnc.port_url("v7")
    subprocess.run(["stty", "-F", path, "1200", "cs8", "-parenb", "cstopb", "raw"], check=True)
    with open(path, "wb") as port:  # hold the pty open while cat writes, as a shell session would
        subprocess.run(f"cat {tape} > {path}", shell=True, check=True)  # noqa: S602 - our own temp paths
        until(lambda: cnc.read("v7.state") == "done", "the read-in ends with M30")
        port.flush()
    assert cnc.read("program.P20") == "N 1 X 10.500 Y- 3.000\nN 2 X 0.000 Y 0.000 G 00 M 02"
