"""The stderr log of `devsim run` through the real CLI (issue 30): device errors with their number
and text, refused host commands and decoded telegrams at -v, -q and -qq, what each device
expects in the banner, a host's line settings as the pty shows them, once per change.

A host here is the test itself: it opens the pty with the termios it chooses (as pyserial does)
and writes a kind's own messages; the log lines are read from the process's stderr with a
timeout."""

from __future__ import annotations

import os
import re
import termios
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from devsim.devices.gms96.codec import LongFrame, control_host, encode, letter
from tests.live.run import Proc, ctl

CMSPAR = getattr(termios, "CMSPAR", 0o10000000000)
_SPEEDS = {4800: termios.B4800, 9600: termios.B9600, 19200: termios.B19200}


def _quick_sers(tmp_path: Path) -> str:
    config = tmp_path / "sers.yaml"
    config.write_text("boot_time: 0.05\n")
    return str(config)


def _configure(fd: int, baud: int, parity: str) -> None:
    """Raw mode at ``baud`` 8``parity``1, the way pyserial sets the termios."""
    attrs = termios.tcgetattr(fd)
    attrs[0] = 0  # iflag
    attrs[1] = 0  # oflag
    attrs[3] = 0  # lflag
    cflag = attrs[2] & ~(termios.CSIZE | termios.PARENB | termios.PARODD | CMSPAR | termios.CSTOPB)
    cflag |= termios.CS8 | termios.CREAD | termios.CLOCAL | (termios.PARENB if parity == "E" else 0)
    attrs[2] = cflag
    attrs[4] = attrs[5] = _SPEEDS[baud]
    try:
        termios.tcsetattr(fd, termios.TCSANOW, attrs)
    except termios.error:  # glibc on a pty refuses a parity it cannot keep (see devsim.transports.pty)
        pass


@contextmanager
def _host(path: str, baud: int = 9600, parity: str = "N") -> Iterator[int]:
    fd = os.open(path, os.O_RDWR | os.O_NOCTTY)
    try:
        _configure(fd, baud, parity)
        yield fd
    finally:
        os.close(fd)


def _pty(proc: Proc, name: str, control: bool = False) -> str:
    path = proc.expect(lambda line: line.startswith(f"{name}: pty ")).split()[-1]
    if control:
        proc.expect(lambda line: line.startswith("control: "))
    proc.expect(lambda line: line == f"{name}: ready")
    return path


def _rest(proc: Proc) -> list[str]:
    """Stop ``proc`` and return its remaining stderr lines."""
    proc.stop()
    lines = []
    while (line := proc.err.get(timeout=10)) is not None:
        lines.append(line)
    return lines


_TIME = r"devsim: \d+\.\d{3} "


def _line(proc: Proc, pattern: str) -> str:
    """The next stderr line that matches ``pattern`` (after the time), within the timeout."""
    regex = re.compile(_TIME + pattern)
    return proc.expect(lambda line: regex.fullmatch(line) is not None, err=True)


def test_v_logs_each_telegram_decoded_and_refused_commands(tmp_path: Path) -> None:
    sim = Proc("run", "sers", "-v", "--config", _quick_sers(tmp_path))
    try:
        path = _pty(sim, "sers")
        with _host(path) as fd:
            os.write(fd, b"#1P11=5\r#1P11?\r")  # P11 takes only 0: the drive answers error 3
            _line(sim, re.escape('sers main → "#1P11=5\\r"'))
            _line(sim, re.escape('sers main → "#1P11?\\r"'))  # one line per message, not per chunk
            _line(sim, re.escape("sers refused 3: ungültig — invalid"))
            _line(sim, re.escape('sers main ← "#1P11=5\\r"'))  # the echo, then the error text
            _line(sim, re.escape('sers main ← "\\n*ung\\xfcltig\\n\\r"'))
    finally:
        sim.stop()


def test_gms96_banner_8n1_host_and_ft12_decoded(tmp_path: Path) -> None:
    """The banner says what the card expects; a host at 8N1 is not logged as 8E1 (a pty does not
    show parity); its FT1.2 frames are logged by their fields, not as hex."""
    sim = Proc("run", "gms96", "-v")
    try:
        assert sim.expect(lambda line: "serving" in line, err=True) == \
            "devsim: serving gms96 (main 9600 8E1, address 3); Ctrl-C to stop"
        path = _pty(sim, "gms96")
        with _host(path, 9600, "N") as fd:
            os.write(fd, encode(LongFrame(control_host(0), 3, letter("A", 10000))))
            line = _line(sim, "gms96 host_settings host settings .*")
            assert line.endswith("host settings 9600 baud, 1 stop bit (data bits and parity not visible)"), line
            _line(sim, re.escape("gms96 main → long C=53 A=3 data=41 10 27 00 letter=A params=10000 fcb=0"))
            _line(sim, re.escape("gms96 main ← single value=E5"))
    finally:
        sim.stop()


def test_a_line_mismatch_is_logged_once_per_change(tmp_path: Path) -> None:
    sim = Proc("run", "sers", "-v", "--config", _quick_sers(tmp_path))
    try:
        path = _pty(sim, "sers")
        seen: list[str] = []
        with _host(path, 4800) as fd:
            for number, baud in ((11, 4800), (12, 4800), (13, 19200)):
                _configure(fd, baud, "N")  # (the same settings again for P12: no change)
                os.write(fd, b"#1P%d?\r" % number)  # (the transport sees the settings when data comes)
                sim.next_match(sim.err, lambda line, n=number: f'→ "#1P{n}?' in line, 15, f"P{number}", seen)
        settings = [line.split(" host settings ", 1)[1] for line in seen if "host_settings" in line]
        assert settings == [
            "4800 baud, 1 stop bit (data bits and parity not visible) (mismatch, device 9600 8N1)",
            "19200 baud, 1 stop bit (data bits and parity not visible) (mismatch, device 9600 8N1)",
        ], seen
    finally:
        sim.stop()


def test_a_host_at_another_rate_on_the_modbus_rtu_line_is_logged_at_q(tmp_path: Path) -> None:
    """Found fuzzing the Modbus RTU facade: a host at 9600 on the default 19200 8E1 RTU line got no
    answer (the line garbles it, as a UART would) and the log said nothing, though a mismatch on
    the device's own port is a warning (-q): the RTU line is the device's ``modbus`` port for
    ``ctl line/capture`` and now for the log too."""
    link = tmp_path / "mb"
    sim = Proc("run", "sers", "-q", "--config", _quick_sers(tmp_path), "--modbus", f"rtu:{link}")
    try:
        sim.expect(lambda line: line.startswith("sers.modbus: "))
        with _host(str(link), 9600) as fd:
            os.write(fd, bytes.fromhex("010300000002c40b"))
            _line(sim, re.escape("sers.modbus host_settings host settings 9600 baud, 1 stop bit") + ".*"
                  + re.escape("(mismatch, device 19200 8E1)"))
    finally:
        sim.stop()


def test_a_drive_error_has_its_number_and_text_at_q(tmp_path: Path) -> None:
    """-q: the limit-switch error with its P11 bit and text, the mismatch; no banner, no
    connect, no refused command (that is -v)."""
    sim = Proc("run", "sers", "-q", "--config", _quick_sers(tmp_path), "--control", f"unix:{tmp_path}/c.sock")
    try:
        path = _pty(sim, "sers", control=True)
        with _host(path, 4800) as fd:
            os.write(fd, b"#1P11=5\r")
            _line(sim, re.escape("sers host_settings host settings 4800 baud, 1 stop bit") + ".*mismatch.*")
        assert ctl(f"unix:{tmp_path}/c.sock", "set", "sers", "input.limit_right", "true").returncode == 0
        _line(sim, re.escape("sers error P11 8192: drive error: limit switch"))
        assert _line(sim, "sers drive_fault .*").endswith("drive_fault axis 1 code 0x7320")  # not a bare "error"
        rest = _rest(sim)
        assert not any("serving" in line or "connect" in line or "refused" in line or "→" in line
                       for line in rest), rest
    finally:
        sim.stop()


def test_qq_prints_nothing_on_stderr_and_the_ports_on_stdout(tmp_path: Path) -> None:
    sim = Proc("run", "sers", "-qq", "--config", _quick_sers(tmp_path), "--control", f"unix:{tmp_path}/c.sock")
    try:
        path = _pty(sim, "sers", control=True)  # stdout: where to connect, whatever the log level
        with _host(path, 4800) as fd:
            os.write(fd, b"#1P11=5\r")
        assert ctl(f"unix:{tmp_path}/c.sock", "set", "sers", "input.limit_right", "true").returncode == 0
        assert ctl(f"unix:{tmp_path}/c.sock", "read", "sers", "axis.position").returncode == 0  # (it has run)
        assert _rest(sim) == []
    finally:
        sim.stop()


def test_an_ip247_module_error_has_its_text_and_no_second_bare_line() -> None:
    """A kind that records ``error N``: the log line is the number with the text of its error
    table, once."""
    from devsim.observe.live_log import attach_log
    from devsim.runtime import Runtime

    runtime = Runtime(virtual=True).start()
    try:
        module = runtime.add_device("ip247").model
        runtime.advance(2)
        lines: list[str] = []
        runtime.call(attach_log, runtime, 1, lines.append)
        runtime.call(module.set_error, None, 5)
        assert lines == ["devsim: 2.000 ip247 error 5: Auftragsliste AG ist voll (AG job list full); PG F85"]
    finally:
        runtime.stop()


def test_up_qq_prints_nothing_on_stderr_and_its_ports_on_stdout(tmp_path: Path) -> None:
    plant = tmp_path / "plant.yaml"
    plant.write_text("devices:\n  - {name: a, kind: sers, transport: {tcp: {port: 0}}, config: {boot_time: 0.05}}\n")
    up = Proc("up", str(plant), "-qq")
    try:
        up.expect(lambda line: line.startswith("a: tcp "))
        up.expect(lambda line: line == "a: ready")
        assert _rest(up) == []  # no file descriptor line, no "plant up" line
    finally:
        up.stop()
