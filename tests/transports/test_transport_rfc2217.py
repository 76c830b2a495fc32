"""Rfc2217Transport with pyserial's rfc2217:// client as the host."""

from __future__ import annotations

import asyncio

import pytest
import serial

from devsim.core.clock import RealClock
from devsim.core.device import SerialSettings
from devsim.transports.line import Line, garble
from devsim.transports.rfc2217 import MAX_SUBOPTION, NegotiatedPort, Rfc2217Transport, _Manager
from tests.transports.transport_helpers import EchoTarget, Recorder

# pyserial's own client thread uses deprecated threading setters.
pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning:serial.rfc2217")


async def test_negotiated_settings_and_round_trip(echo: Recorder) -> None:
    transport = Rfc2217Transport()
    await transport.start(echo)
    assert transport.url == f"rfc2217://127.0.0.1:{transport.port}"
    try:
        data = b"#ON\r\xff\x00\x11\x13"  # 0xFF is Telnet IAC: must be escaped both ways

        def host() -> tuple[bytes, bytes]:
            port = serial.serial_for_url(transport.url, baudrate=4800, timeout=3)
            try:
                port.write(data)
                first = port.read(len(data))
                port.baudrate = 19200  # reconfigured while open
                port.write(b"Z")
                second = port.read(1)
            finally:
                port.close()
            return first, second

        first, second = await asyncio.to_thread(host)
        assert first == data
        assert second == b"Z"
        assert echo.data == data + b"Z"
        assert echo.settings[0].baudrate == 4800
        assert echo.settings[0] == SerialSettings(4800, 8, "N", 1)
        assert echo.settings[-1].baudrate == 19200
        await echo.wait_for(lambda: echo.disconnects == 1)
    finally:
        await transport.close()


async def test_frame_format_mismatch_reaches_the_line() -> None:
    device = SerialSettings(9600, 7, "E", 1)
    target = EchoTarget(device)
    line = Line(target, RealClock())
    mismatch_seen: list[bool] = []
    original_feed = target.feed

    def feed(data: bytes) -> None:
        mismatch_seen.append(line.mismatch)
        original_feed(data)

    target.feed = feed  # type: ignore[method-assign]
    transport = Rfc2217Transport()
    await transport.start(line)
    try:

        def host() -> None:
            with serial.serial_for_url(transport.url, baudrate=9600, timeout=3) as port:
                port.write(b"#ON\r")
                port.flush()

        await asyncio.to_thread(host)
        await asyncio.wait_for(target.event.wait(), 3)
        assert mismatch_seen == [True]  # 8N1 host, 7E1 device
        assert bytes(target.received) == garble(b"#ON\r", SerialSettings(9600), device) != b"#ON\r"
    finally:
        await transport.close()
        line.close()


async def _read_until(reader: asyncio.StreamReader, marker: bytes) -> bytes:
    """What the server sends until ``marker`` has come (the test fails if it closes first)."""
    answers = b""
    while marker not in answers:
        chunk = await asyncio.wait_for(reader.read(4096), 5)
        assert chunk, f"the server closed the connection after {answers!r}"
        answers += chunk
    return answers


def _option(command: int, value: bytes) -> bytes:
    """IAC SB COM-PORT-OPTION command value IAC SE (client to server)."""
    return bytes([255, 250, 44, command]) + value.replace(b"\xff", b"\xff\xff") + bytes([255, 240])


async def test_an_end_of_subnegotiation_outside_one_is_ignored(echo: Recorder) -> None:
    """IAC SE with no IAC SB before it ends nothing (RFC 854): it is dropped and the data around it
    goes on.  Found by the soak's raw Telnet garbage against ``devsim run sers --rfc2217``:
    pyserial's filter called ``bytes(None)`` for it, the TypeError escaped into asyncio
    ("Fatal error: protocol.buffer_updated() call failed", a traceback on stderr) and the
    connection was dropped."""
    transport = Rfc2217Transport()
    await transport.start(echo)
    try:
        reader, writer = await asyncio.open_connection("127.0.0.1", transport.port)
        writer.write(b"#O\xff\xf0N\r" + _option(3, b"\x03"))  # (then SET-PARITY even: its reply ends the wait)
        await writer.drain()
        await _read_until(reader, b"\xff\xfa\x2c\x67\x03\xff\xf0")
        assert echo.data == b"#ON\r"
        writer.close()
        await writer.wait_closed()
    finally:
        await transport.close()


async def test_a_malformed_setting_is_answered_with_the_current_one(echo: Recorder) -> None:
    """A parity or stop size code RFC 2217 does not define, values cut short, an empty mask: each
    setting is answered with the current value and the connection goes on carrying data.  (pyserial's
    server side raised KeyError or struct.error out of its telnet filter for these: the connection
    was dropped with a traceback.)"""
    transport = Rfc2217Transport()
    await transport.start(echo)
    try:
        reader, writer = await asyncio.open_connection("127.0.0.1", transport.port)
        writer.write(_option(3, b"\x09") + _option(4, b"\x09") + _option(1, b"\x00\x01") + _option(2, b"")
                     + _option(10, b"") + _option(3, b"\x03") + b"#ON\r")  # (3: SET-PARITY 3, even: taken)
        await writer.drain()
        answers = await _read_until(reader, b"#ON\r")
        # server replies (command + 100): parity 9 -> still none (1), stop size 9 -> still one (1),
        # the baud rate cut short -> 9600, the data size cut short -> 8, then even parity (3)
        replies = [answers[i + 3:answers.index(b"\xff\xf0", i)] for i in range(len(answers))
                   if answers.startswith(b"\xff\xfa\x2c", i)]
        assert replies == [b"\x67\x01", b"\x68\x01", b"\x65\x00\x00\x25\x80", b"\x66\x08", b"\x67\x03"]
        assert echo.data == b"#ON\r" and echo.settings[-1] == SerialSettings(9600, 8, "E", 1)
        writer.close()
        await writer.wait_closed()
    finally:
        await transport.close()


def test_a_subnegotiation_that_does_not_end_keeps_at_most_max_suboption_bytes() -> None:
    """IAC SB and then bytes with no IAC SE: the subnegotiation keeps its first MAX_SUBOPTION
    bytes, and its IAC SE still ends it (before: every byte the client sent after the IAC SB was
    kept, a megabyte here)."""
    sent: list[bytes] = []

    class Connection:
        write = staticmethod(sent.append)

    port = NegotiatedPort(SerialSettings(9600), lambda: None)
    manager = _Manager(port, Connection())
    set_baudrate = b"\xff\xfa\x2c\x01" + (19200).to_bytes(4, "big")
    assert list(manager.filter(set_baudrate + b"x" * 1_000_000)) == []
    assert manager.suboption is not None and len(manager.suboption) <= MAX_SUBOPTION
    assert b"".join(manager.filter(b"\xff\xf0#ON\r")) == b"#ON\r"  # ended: data again
    assert port.baudrate == 19200
