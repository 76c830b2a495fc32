"""Gms96Client against a tiny fake card served on a real pty (and on raw TCP) by the runtime.

The fake card is not the GMS96 simulator: it knows just enough to answer E5h, a T reply and a
K frame, and records what it received, so the tests check the client's bytes on the wire.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any, ClassVar

import pytest
import serial

from devsim.core.device import Device, Face
from devsim.devices.gms96.client import (
    Gms96Client,
    Gms96Error,
    Gms96NoData,
    Gms96ReplyError,
    Gms96Timeout,
    t_param_count,
)
from devsim.devices.gms96.codec import (
    ACK,
    FCB,
    FCV,
    Frame,
    FrameDecoder,
    FrameError,
    LongFrame,
    ShortFrame,
    SingleChar,
    encode,
    k_frame,
    letter,
    parse_letter,
    short_command,
    short_command_number,
    short_extension_device,
    t_reply,
    to_s24,
)
from devsim.runtime import Runtime
from devsim.transports.pty import PtyTransport
from devsim.transports.tcp import TcpTransport


class FakeCard(Face):
    """Answers T0 / T1;0 / T3;0 with a T reply, #1 with a K frame, everything else with E5h;
    ``+`` moves a position.  With ``e_version`` a repeated FCV=1 frame with the same FCB is
    answered again but not executed (spec §3.9)."""

    def __init__(self, model: Any, port: Any, address: int = 3, e_version: bool = False) -> None:
        super().__init__(model, port)
        self.address = address
        self.e_version = e_version
        self.decoder = FrameDecoder(short_extension=short_extension_device)
        self.received: list[Frame] = []
        self.errors: list[FrameError] = []
        self.position = 0
        self.k: int | None = 0x40
        self.mb4: int | None = 23
        self.short_data: list[tuple[int, bytes]] = []
        self.silent = False
        self._last_fcb: int | None = None
        self._last_reply = b""

    def feed(self, data: bytes) -> None:
        for item in self.decoder.feed(data, self.model.clock.now()):
            if isinstance(item, FrameError):
                self.errors.append(item)
                continue
            self.received.append(item)
            if self.silent or isinstance(item, SingleChar) or item.address != self.address:
                continue
            reply = self._answer(item)
            self.send(reply)

    def _answer(self, frame: ShortFrame | LongFrame) -> bytes:
        if isinstance(frame, ShortFrame):
            number = short_command_number(frame.control)
            if number == 1 and self.k is not None:
                reply = encode(k_frame(self.k, self.address, self.mb4))
                self.mb4 = None
                return reply
            if number == 0:
                self._last_fcb = None  # E-version: #0 / reset of remote link resynchronises the FCB
            self.short_data.append((number, frame.extension))
            return bytes([ACK])
        if self.e_version and frame.control & FCV:
            fcb = 1 if frame.control & FCB else 0
            if fcb == self._last_fcb:
                return self._last_reply
            self._last_fcb = fcb
        parsed = parse_letter(frame.data)
        assert parsed is not None
        command, (p1, p2, _p3), _count = parsed
        reply = bytes([ACK])
        if command == "+":
            self.position += p1
        elif command == "T":
            if (p1, p2) == (0, 0):
                reply = encode(t_reply(self.address, ord("@"), to_s24(self.position)))
            elif (p1, p2) == (1, 0):
                reply = encode(t_reply(self.address, ord("V"), (404).to_bytes(2, "little")))
            elif (p1, p2) == (3, 0):
                reply = encode(t_reply(self.address, 0x08, b""))
        self._last_reply = reply
        return reply


class FakeCardDevice(Device):
    kind = "fake-gms96"
    face_classes: ClassVar[dict[str, Any]] = {"main": FakeCard}


class Rig:
    def __init__(self, runtime: Runtime, card: FakeCard, port: serial.SerialBase) -> None:
        self.runtime = runtime
        self.card = card
        self.port = port

    def received(self) -> list[Frame]:
        return self.runtime.call(lambda: list(self.card.received))

    def wire(self) -> list[bytes]:
        return [encode(f) for f in self.received()]


@pytest.fixture
def rig_factory() -> Iterator[Any]:
    made: list[Rig] = []

    def make(*, e_version: bool = False, tcp: bool = False) -> Rig:
        runtime = Runtime().start()
        device = runtime.call(lambda: FakeCardDevice(clock=runtime.clock))
        card = device.face()
        assert isinstance(card, FakeCard)
        card.e_version = e_version
        transport = TcpTransport() if tcp else PtyTransport()
        runtime.serve_sync(device, transport)
        port = serial.serial_for_url(transport.url, baudrate=9600, timeout=1.0)
        rig = Rig(runtime, card, port)
        made.append(rig)
        return rig

    yield make
    for rig in made:
        rig.port.close()
        rig.runtime.stop()


@pytest.fixture
def rig(rig_factory: Any) -> Rig:
    made: Rig = rig_factory()
    return made


def test_send_letter_alternates_fcb(rig: Rig) -> None:
    client = Gms96Client(rig.port, 3)
    assert client.send_letter("A", 10000) == SingleChar(ACK)
    assert client.send_letter("+", 1000) == SingleChar(ACK)
    assert client.send_letter("q") == SingleChar(ACK)
    assert rig.wire() == [
        bytes.fromhex("68 06 06 68 53 03 41 10 27 00 CE 16"),  # spec §3.11 A10000
        bytes.fromhex("68 06 06 68 73 03 2B E8 03 00 8C 16"),  # spec §3.11 +1000, FCB=1
        bytes.fromhex("68 03 03 68 53 03 71 C7 16"),
    ]


def test_read_position_version_and_status(rig: Rig) -> None:
    client = Gms96Client(rig.port, 3)
    client.send_letter("+", -10000)
    assert client.read(0) == (0x40, 0xFFD8F0, bytes.fromhex("F0 D8 FF"))
    assert client.read(1, 0) == (ord("V"), 404, b"\x94\x01")
    assert client.read(3, 0) == (0x08, 0, b"")
    requests = [f for f in rig.received() if isinstance(f, LongFrame) and f.data[:1] == b"T"]
    assert [f.data for f in requests] == [letter("T", 0), letter("T", 1, 0), letter("T", 3, 0)]


def test_read_without_data_raises(rig: Rig) -> None:
    client = Gms96Client(rig.port, 3)
    with pytest.raises(Gms96NoData):
        client.read(9, 9)
    rig.runtime.call(lambda: setattr(rig.card, "k", None))  # now #1 gets E5h instead of a K frame
    with pytest.raises(Gms96ReplyError):
        client.status()


def test_t_param_count_matches_spec_vectors() -> None:
    assert t_param_count(0, 0, 0) == 1  # T0: L = 6
    assert t_param_count(1, 0, 0) == 2  # T1;0: L = 9
    assert t_param_count(1, 1, 0) == 3  # T1;1;0: L = 12
    assert t_param_count(1, 4, 0) == 2
    assert t_param_count(1, 6, 8) == 3
    assert t_param_count(3, 0, 0) == 2
    assert t_param_count(5, 8, 1) == 3


def test_status_with_and_without_message(rig: Rig) -> None:
    client = Gms96Client(rig.port, 3)
    assert client.status() == (0x42, 23)  # spec §3.11: 10 42 03 17 5C 16
    assert client.status() == (0x40, None)  # MB4 cleared by the previous status
    assert rig.wire()[:2] == [bytes.fromhex("10 01 03 04 16")] * 2


def test_short_commands(rig: Rig) -> None:
    client = Gms96Client(rig.port, 3)
    client.abort()
    client.spindle_speed(1500)
    client.override(80)
    assert rig.wire() == [
        bytes.fromhex("10 00 03 03 16"),
        bytes.fromhex("10 0A 03 DC 05 EE 16"),
        bytes.fromhex("10 0B 03 50 5E 16"),
    ]
    assert rig.runtime.call(lambda: list(rig.card.short_data)) == [(0, b""), (8, b"\xdc\x05"), (9, b"P")]
    with pytest.raises(ValueError):
        client.spindle_speed(70000)
    with pytest.raises(ValueError):
        client.override(300)


def test_repeat_last_resends_identical_frame_s_version(rig: Rig) -> None:
    """S-version hazard: the repeat is executed again (spec §3.9)."""
    client = Gms96Client(rig.port, 3)
    assert client.send_letter("+", 1000) == SingleChar(ACK)
    assert client.repeat_last() == SingleChar(ACK)
    wire = rig.wire()
    assert wire[0] == wire[1] == bytes.fromhex("68 06 06 68 53 03 2B E8 03 00 6C 16")
    # The next new command toggles the FCB again.
    client.send_letter("+", 1000)
    assert rig.wire()[2] == bytes.fromhex("68 06 06 68 73 03 2B E8 03 00 8C 16")
    assert rig.runtime.call(lambda: rig.card.position) == 3000


def test_repeat_last_is_suppressed_by_an_e_version_card(rig_factory: Any) -> None:
    rig = rig_factory(e_version=True)
    client = Gms96Client(rig.port, 3, e_version=True)
    client.send_letter("+", 1000)
    assert client.repeat_last() == SingleChar(ACK)
    assert client.read(0)[1] == 1000
    client.send_letter("+", 1000)
    assert client.read(0)[1] == 2000


def test_reset_link(rig_factory: Any) -> None:
    rig = rig_factory(e_version=True)
    client = Gms96Client(rig.port, 3, e_version=True)
    client.send_letter("+", 1)  # FCB 0
    assert client.reset_link() == SingleChar(ACK)
    client.send_letter("+", 1)  # after a reset the first FCB is 1 (IEC 60870-5-2)
    wire = rig.wire()
    assert wire[1] == bytes.fromhex("10 40 03 43 16")
    assert wire[2][4] == 0x73
    with pytest.raises(Gms96Error):
        Gms96Client(rig.port, 3).reset_link()  # S-version: no link reset
    with pytest.raises(Gms96Error):
        Gms96Client(rig.port, 3).repeat_last()  # nothing sent yet


def test_timeout_when_the_card_is_silent(rig: Rig) -> None:
    client = Gms96Client(rig.port, 3, timeout=0.1)
    rig.runtime.call(lambda: setattr(rig.card, "silent", True))
    assert client.send_letter("A", 1) is None
    with pytest.raises(Gms96Timeout):
        client.read(0)
    with pytest.raises(Gms96Timeout):
        client.status()
    with pytest.raises(Gms96Timeout):
        client.abort()


def test_other_address_gets_no_answer(rig: Rig) -> None:
    client = Gms96Client(rig.port, 4, timeout=0.1)
    assert client.send_letter("A", 1) is None
    assert rig.wire() == [bytes.fromhex("68 06 06 68 53 04 41 01 00 00 99 16")]


def test_late_reply_is_not_taken_for_the_next_one(rig: Rig) -> None:
    """Input left over from an earlier exchange is dropped before a new request."""
    client = Gms96Client(rig.port, 3)
    rig.runtime.call(lambda: rig.card.send(b"\xe5\xe5"))  # stray bytes the host did not ask for
    rig.port.read(1)  # make sure they arrived (one is still buffered)
    assert client.status() == (0x42, 23)


def test_client_over_tcp(rig_factory: Any) -> None:
    rig = rig_factory(tcp=True)
    client = Gms96Client(rig.port, 3)
    assert client.send_letter("+", 5) == SingleChar(ACK)
    assert client.read(0)[1] == 5
    assert client.status() == (0x42, 23)


def test_raw_frames_and_errors(rig: Rig) -> None:
    client = Gms96Client(rig.port, 3)
    assert client.transact(short_command(1, 3)) == k_frame(0x40, 3, 23)
    assert client.exchange(bytes.fromhex("10 01 03 04 16")) == k_frame(0x40, 3, None)
    assert client.last_reply == k_frame(0x40, 3, None)
    assert not client.acd and not client.dfc


def test_client_works_on_a_pty_opened_with_even_parity() -> None:
    """A Linux pty refuses parity E re-configuration; the client must still be usable."""
    import os
    import threading
    import tty

    import serial

    from devsim.devices.gms96.client import Gms96Client

    master, slave = os.openpty()
    tty.setraw(master)

    def card() -> None:  # answers the #0 frame with E5h
        received = b""
        while len(received) < 5:
            received += os.read(master, 5 - len(received))
        os.write(master, bytes([0xE5]))

    try:
        port = serial.Serial(os.ttyname(slave), 9600, parity="E", timeout=0.5)
        client = Gms96Client(port, 3, timeout=1.0)
        thread = threading.Thread(target=card)
        thread.start()
        assert client.exchange(b"\x10\x00\x03\x03\x16") is not None
        thread.join(2)
        port.close()
    finally:
        os.close(master)
        os.close(slave)
