"""The AS511 link of the PG port on the real pty, in virtual time (spec ip247.md §3.5.1, §3.5.2):
the 500 ms timeout is a gap on the line, so it counts from the last character on the wire, also
when that character is the device's own, at the end of a long data block sent at 9600 8E1."""

from __future__ import annotations

from devsim.devices.ip247.as511 import TIMEOUT
from tests.ip247.helpers import Module

CHAR = 11 / 9600  # one character at 9600 8E1: start, 8 data, parity, stop
BIG = "%  7 LANG\n" + "".join(f"N{i} X{i} F1000\n" for i in range(1, 70)) + "N70 M02\n"


def _read_program_until_the_data(mod: Module) -> float:
    """READ_REC BA69 program 7 (§3.6.3) up to the device's data block and its DLE ETX; the
    seconds the device's characters take on the wire (all sent at one instant of virtual time,
    one after the other)."""
    port = mod.port
    for sent, answer in (("02", "10 06"), ("64", "02"), ("10 06", "16 10 03")):
        port.write(bytes.fromhex(sent))
        assert port.read(len(bytes.fromhex(answer))) == bytes.fromhex(answer), sent
    port.write(bytes.fromhex("10 06 04 45 07 00 10 04"))
    assert port.read(3) == bytes.fromhex("10 06 02")
    port.write(bytes.fromhex("10 06"))
    data = port.read_until(b"\x10\x03", 4096)
    assert data.endswith(b"\x10\x03") and data[:3] == bytes.fromhex("00 04 45")
    return (2 + 1 + 3 + 3 + len(data)) * CHAR


def test_the_timeout_runs_from_the_devices_last_character(mod: Module) -> None:
    """A program of about 1000 bytes takes more than a second on the wire at 9600 8E1; the PG's
    DLE ACK 0.4 s after the block's last character is inside the transaction (§3.5.1: "no gap
    of 500 ms or more"), and the transaction goes on to its end."""
    mod.device.set("program.7", BIG)
    wire = _read_program_until_the_data(mod)
    assert wire > 2 * TIMEOUT  # (the device is still sending when 500 ms after the PG's byte are over)
    mod.clock.advance(wire + TIMEOUT - 0.1)
    mod.port.write(bytes.fromhex("10 06"))
    assert mod.port.read(1) == b"\x02"
    mod.port.write(bytes.fromhex("10 06"))
    assert mod.port.read(3) == bytes.fromhex("12 10 03")
    mod.port.write(bytes.fromhex("10 06"))
    assert mod.device.read("program.7") == BIG


def test_a_gap_of_500_ms_after_the_data_still_abandons_it(mod: Module) -> None:
    """The same read, the PG silent for 500 ms after the block's last character: the device is
    back to idle, the late DLE ACK is noise, and the next STX opens a transaction."""
    mod.device.set("program.7", BIG)
    mod.clock.advance(_read_program_until_the_data(mod) + TIMEOUT + 0.001)
    mod.port.write(bytes.fromhex("10 06 02"))
    assert mod.port.read(2) == bytes.fromhex("10 06")  # (a live transaction would answer 02 first)
