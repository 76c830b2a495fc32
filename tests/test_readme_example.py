import re

import pytest
import serial

# -- the host code under test (plain pyserial) --------------------------------------------------
ANSWER = re.compile(rb"\n(?:ok(\d)|\*([^\n]*))\n\r")


class DriveError(Exception):
    pass


def ask(port, line, check=True):
    """Send one line to the drive; return its answer, raise DriveError on an error."""
    port.write(line.encode("latin-1"))
    reply = b""
    while (match := ANSWER.search(reply)) is None:
        byte = port.read(1)
        if not byte:
            raise TimeoutError(f"no answer to {line!r}")
        reply += byte
    if match.group(2) is not None:  # \n*<message>\n\r
        raise DriveError(match.group(2).decode("latin-1"))
    if check and match.group(1) == b"4":  # ok4: the drive has an error
        raise DriveError("drive error " + ask(port, "#P11?\r", check=False).split("\r")[1].strip())
    return reply.decode("latin-1")


def home_and_move(url, target, wait):
    """Home the drive, move it to ``target`` degrees; ``wait()`` is called between polls."""
    with serial.serial_for_url(url, baudrate=9600, timeout=2) as port:
        for line in ("#1\r", "#ON\r", "#H\r"):
            ask(port, line)
        while "POS=1" not in ask(port, "#POS?\r"):
            wait()
        ask(port, f"#W={target} E\r")
        while "POS=1" not in ask(port, "#POS?\r"):
            wait()
        return ask(port, "#P51?\r").split("\r")[1].strip()


# -- the tests ------------------------------------------------------------------------------------
CONFIG = {"axis": {"reference_low": 1280}}  # reference cam 36° from the power-on position


def test_home_and_move(devsim_device):
    drive = devsim_device("sers", CONFIG)  # on a pty, virtual time, booted
    position = home_and_move(drive.port, 3600, wait=lambda: drive.advance(0.1))
    assert position == "P51=3600°"
    assert drive.read("axis.position") == pytest.approx(1280 + 10 * 12800)


def test_limit_switch_trips_mid_move(devsim_device):
    drive = devsim_device("sers", CONFIG)

    def wait():  # the host polls; the test moves simulated time
        drive.advance(0.1)
        if drive.read("axis.position") > 20_000:  # mid-move: the right limit switch opens
            drive.set("input.limit_right", True)

    with pytest.raises(DriveError, match="P11=8192"):  # "Fehler Lagegrenzwert"
        home_and_move(drive.port, 3600, wait)
    assert drive.run_until(lambda device: not device.read("motion"), timeout=5)  # braked
    assert drive.read("display") == {"char": "c", "blinking": False}
    with serial.Serial(drive.port, 9600, timeout=2) as port:
        with pytest.raises(DriveError, match="Endschalter offen"):
            ask(port, "#E\r")  # a move towards the open switch is refused
