"""``devsim run gms96 -v``: a Langsatz whose command byte is a control character or beyond ASCII
(manual §2.3: one command character) is logged on one line, escaped, like every telegram and
event (observe/traffic_log.py, runtime/watch_stream.describe)."""

from __future__ import annotations

import serial

from devsim.devices.gms96 import codec
from devsim.devices.gms96.client import Gms96Client
from tests.test_cli import Sim

COMMAND_BYTES = (0x0A, 0x0D, 0x1B, 0x1C, 0x0B, 0x85, 0x9B, 0xDF)


def test_a_command_byte_that_is_no_printable_ascii_is_logged_escaped_on_one_line() -> None:
    sim = Sim("gms96", "--pty", "-v", "--no-control")
    try:
        seen = sim.read_until("gms96: ready")
        with serial.Serial(seen["gms96"].split()[1], 9600, parity="E", timeout=2) as port:
            card = Gms96Client(port, 3, timeout=2.0)
            for byte in COMMAND_BYTES:
                card.fcb ^= 1
                reply = card.transact(codec.LongFrame(codec.control_host(card.fcb), 3, bytes([byte, 0, 0, 0])))
                assert reply == codec.SingleChar(0xE5)  # an unknown command (link.unknown_command_reply: ack)
            card.send_letter("T", 0)  # the last line the log must reach
    finally:
        code, err = sim.stop()
    assert code == 0
    lines = err.splitlines()
    assert all(line.startswith("devsim: ") for line in lines), [line for line in lines if not line.startswith("devsim: ")]
    assert not any(c in err for c in "\x1b\x1c\x0b\x85\x9b\u2028"), "a control character reached the log"
    for byte in COMMAND_BYTES:
        shown = chr(byte).encode("unicode_escape").decode("ascii")
        assert any(f"data={byte:02x} 00 00 00 letter={shown} " in line for line in lines), shown
    assert any(line.endswith(' event "cmd_\\u001b"') for line in lines)
