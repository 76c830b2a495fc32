"""SERS serial interface through a pty: echo modes, framing, errors, bad input (§4.1, §4.2)."""

from __future__ import annotations

import logging
import os
import termios

import pytest
import serial

from tests.sers.conftest import Host, Plant


@pytest.mark.manual("§4.1", "a CR and/or a LF are acknowledged with one 'ok' and a digit")
def test_crlf_pair_gives_one_acknowledgement(sers: Plant) -> None:
    sers.host.send("#\r\n#P11?\r")
    sers.host.expect(b"#\r\nok1\n\r\n#P11?\rP11=0\n\r\nok1\n\r")


@pytest.mark.manual("§4.1", "every line ends with CR (#13) or LF (#10)")
def test_lf_alone_ends_a_line(sers: Plant) -> None:
    assert sers.host.ask("#ON\n") == b"#ON\n\nok1\n\r"


@pytest.mark.manual("§4.2", "all keywords may be written upper or lower case")
def test_keywords_are_case_insensitive(sers: Plant) -> None:
    assert sers.host.ask("#on v=1000\r") == b"#on v=1000\r\nok1\n\r"
    assert sers.host.ask("#v?\r") == b"#v?\rV=1000U/min\n\r\nok1\n\r"


def test_echo_mode_0_echoes_like_mode_1(plant_factory) -> None:
    plant = plant_factory({"params": {"P1017": 0}})
    assert plant.host.ask("#P11?\r") == b"#P11?\rP11=0\n\r\nok1\n\r"


@pytest.mark.manual("§4.1", "in mode HANDSHAKE_RS485 error messages are always sent only after the line end")
def test_rs485_mode_reports_errors_only_at_line_end(plant_factory) -> None:
    plant = plant_factory({"params": {"P1017": 2}})
    plant.host.send("#XY ON\r")
    plant.host.expect(b"\n*= oder ? erwartet\n\r")
    # the statements after the error were not executed, and no ok followed
    assert plant.host.ask("#P134?\r") == b"P134=0\n\r\nok3\n\r"


def test_switching_echo_mode_takes_effect_on_the_next_character(sers: Plant) -> None:
    sers.host.send("#P1017=2\r")
    sers.host.expect(b"#P1017=2\r\nok1\n\r")
    assert sers.host.ask("#P1017=1\r") == b"\nok1\n\r"
    assert sers.host.ask("#\r") == b"#\r\nok1\n\r"


@pytest.mark.manual("§4.8.2.5", "P1133 can also be read with the command VER")
def test_query_forms_and_aliases(sers: Plant) -> None:
    host = sers.host
    assert host.ask("#P91?\r") == b"#P91?\rP91=100U/min\n\r\nok1\n\r"
    assert host.ask("#A?\r") == "#A?\rA=100rad/s²\n\r\nok1\n\r".encode("latin-1")
    assert host.ask("#W=25.5\r") == b"#W=25.5\r\nok1\n\r"
    assert host.ask("#W?\r") == "#W?\rW=25.5°\n\r\nok1\n\r".encode("latin-1")
    assert host.ask("#P123??\r") == b"#P123??\rVorschubkonstante\n\r\nok1\n\r"
    assert host.ask("#VER\r") == b"#VER\rP1133=120901\n\r\nok1\n\r"
    assert host.ask("#P265=1\r") == b"#P265=1\r\nok1\n\r"
    assert host.ask("#V=0\r") == b"#V=0\r\n*V too small\n\r"


def test_unknown_parameter_and_read_only(sers: Plant) -> None:
    assert sers.host.ask("#P9999?\r") == b"#P9999?\r\n*Parameter nicht vorhanden\n\r"
    assert sers.host.ask("#P1133=5\r") == b"#P1133=5\r\n*Wert kann nicht geschrieben werden\n\r"
    assert sers.read("param.P1137") == 105


@pytest.mark.manual("§4.1", "a wrong value is reported, depending on the value, already while it is being entered")
def test_statement_errors_stop_the_rest_of_the_line(sers: Plant) -> None:
    sers.host.send("#V=20000 ON\r")
    # the value error is reported as soon as the value is complete; the rest is only echoed
    sers.host.expect("#V=20000 \n*V zu groß\n\rON\r".encode("latin-1"))
    assert sers.read("energized") is False


@pytest.mark.manual("§4.1", "every line sent to a SERS must begin with '#'")
def test_bytes_before_hash_are_ignored(sers: Plant) -> None:
    assert sers.host.ask("garbage\x00\x7f\r#P11?\r") == b"#P11?\rP11=0\n\r\nok1\n\r"


def test_binary_noise_inside_a_line(sers: Plant) -> None:
    noise = bytes(range(0x80, 0x90))
    sers.host.send(b"#" + noise + b"\r")
    reply = sers.host.read_until_ack()
    assert reply.startswith(b"#\x80")
    assert b"*Anweisung erwartet" in reply
    assert sers.host.ask("#P11?\r").endswith(b"P11=0\n\r\nok3\n\r")


def test_nul_bytes_inside_a_line(sers: Plant) -> None:
    reply = sers.host.ask(b"#\x00ON\r")  # type: ignore[arg-type]
    assert b"*Anweisung erwartet" in reply
    assert sers.read("energized") is False


@pytest.mark.manual("§4.1", "at most 60 characters in a line")
@pytest.mark.manual("§4.8.3.1", "P12 1024 RS232 buffer overflow (too many characters received in a short time); errno 124")
def test_overlong_line_is_cut_at_60_characters(sers: Plant) -> None:
    line = "#" + "W=1 " * 20  # 81 characters
    reply = sers.host.ask(line + "\r")
    assert reply == (line + "\r").encode() + "\n*RS232 Pufferüberlauf\n\r".encode("latin-1")
    assert sers.read("P12") & 1024
    assert sers.read("param.P1137") == 124


def test_a_hash_inside_a_line_restarts_with_a_new_address(plant_factory) -> None:
    plant = plant_factory({"address": 1}, {"address": 2})
    plant.host.ask("#1 V=500 #2 V=700\r")
    assert plant.read("param.V", "sers1") == 500
    assert plant.read("param.V", "sers2") == 700


def test_input_during_boot_is_discarded(plant_factory) -> None:
    plant = plant_factory({}, boot=False)
    assert plant.read("display") == {"char": "-", "blinking": False}
    plant.host.send("#ON\r")
    plant.wait_received(4)
    plant.advance(2.0)
    assert plant.read("energized") is False
    assert plant.host.ask("#\r") == b"#\r\nok1\n\r"


def test_host_reconnects_and_device_keeps_serving(sers: Plant) -> None:
    port = sers.transport.address
    sers.host.ask("#ON\r")
    for _ in range(5):
        sers.host.close()
        sers.host = Host(port)
        assert sers.host.ask("#P134?\r") == b"#P134?\rP134=7\n\r\nok1\n\r"


def test_host_disconnects_mid_line(sers: Plant) -> None:
    port = sers.transport.address
    sers.host.send("#V=12")
    sers.host.expect(b"#V=12")
    sers.host.close()
    sers.host = Host(port)
    # the next line starts with '#', which restarts parsing: the half line is not glued on
    assert sers.host.ask("#V?\r") == b"#V?\rV=12U/min\n\r\nok1\n\r"


@pytest.mark.manual("§3.1.3", "the baud rate is set on DIP switch 1 bits 1-3 (1200..115200); a host at another rate is not understood")
def test_baud_mismatch_garbles_and_is_reported(sers: Plant) -> None:
    port = sers.transport.address
    sers.host.close()
    host = Host(port, baudrate=19200)
    sers.host = host
    before = sers.runtime.state("sers")["line"]["bytes_in"]
    host.send("#ON\r")
    sers.wait_received(before + 1)
    status = sers.runtime.state("sers")["line"]
    assert status["mismatch"] is True
    assert sers.read("energized") is False  # the drive saw garbage, not "#ON"
    host.port.baudrate = 9600
    host.port.reset_input_buffer()
    host.ask("#\r")  # ends whatever half line the garbage left behind
    assert host.ask("#ON\r") == b"#ON\r\nok1\n\r"
    assert sers.runtime.state("sers")["line"]["mismatch"] is False


def test_a_host_at_b0_hangs_up_and_gets_nothing_across(sers: Plant, caplog: pytest.LogCaptureFixture) -> None:
    """B0, POSIX's hang-up, as the host's rate: the line reports 0 baud as a mismatch and the
    device reads nothing; the simulator goes on.  (The host's bytes at 0 baud raised ValueError in
    the pty's reader: asyncio logged the traceback and the chunk was lost to the trace too.)"""
    port = sers.transport.address
    sers.host.close()
    fd = os.open(port, os.O_RDWR | os.O_NOCTTY)
    try:
        attrs = termios.tcgetattr(fd)
        attrs[4] = attrs[5] = termios.B0
        termios.tcsetattr(fd, termios.TCSANOW, attrs)
        before = sers.runtime.state("sers")["line"]["bytes_in"]
        with caplog.at_level(logging.ERROR):
            os.write(fd, b"#ON\r")
            sers.wait_received(before + 4)
            line = sers.runtime.state("sers")["line"]  # (in the loop: after the chunk's callback ended)
        assert line["mismatch"] is True and line["host"]["baudrate"] == 0
        assert sers.read("energized") is False
        assert [record.getMessage() for record in caplog.records if record.levelno >= logging.ERROR] == []
    finally:
        os.close(fd)
    sers.host = Host(port)
    assert sers.host.ask("#ON\r") == b"#ON\r\nok1\n\r"


def test_raw_bytes_pass_the_pty_unchanged(sers: Plant) -> None:
    """XON, XOFF, DEL, NUL, CR and LF reach the device as sent (raw pty, echo mode)."""
    sers.host.send(b"#\x11\x13\x7f\x00\r")
    reply = sers.host.read_until_ack()
    assert reply.startswith(b"#\x11")


def test_pyserial_can_open_the_link_path(plant_factory, tmp_path) -> None:
    from devsim.runtime import Runtime
    from devsim.transports.pty import PtyTransport

    runtime = Runtime(virtual=True).start()
    try:
        device = runtime.add_device("sers", "sers", {})
        link = tmp_path / "ttySERS"
        runtime.serve_sync(device, PtyTransport(link=str(link)))
        runtime.advance(2.0)
        with serial.Serial(str(link), 9600, timeout=2) as port:
            port.write(b"#P11?\r")
            assert port.read(len(b"#P11?\rP11=0\n\r\nok1\n\r")) == b"#P11?\rP11=0\n\r\nok1\n\r"
    finally:
        runtime.stop()
    assert not link.exists()
