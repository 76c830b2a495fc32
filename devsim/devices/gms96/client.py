"""A small GMS96 host (master) on top of any pyserial port – a starting point for host code.

The client is the primary station of the DIN 19244 / FT1.2 link (spec §3.4): it sends one
frame, waits for the card's reply or a timeout, and only then sends the next.  Letter commands
go in a Langsatz with FCV = 1, FC = 3 and an FCB that alternates for every new command
(``53h`` / ``73h``, spec §3.5, §3.9); :meth:`Gms96Client.repeat_last` re-sends the previous
frame unchanged, which is what a host does after a lost reply (an E-version card then answers
without executing again, an S-version card executes twice).

Works with a pty path, ``socket://`` or ``rfc2217://`` – anything ``serial.serial_for_url``
opens::

    port = serial.serial_for_url("/tmp/gms96", baudrate=9600, parity="E")
    card = Gms96Client(port, address=3)
    card.send_letter("A", 10000)        # -> SingleChar(0xE5)
    card.read(0)                        # -> (0x40, position as unsigned int, raw bytes)
    card.status()                       # -> (K, MB4 or None)

The client sets ``port.timeout`` to a short poll interval; its own ``timeout`` bounds each
exchange.
"""

from __future__ import annotations

import termios
import time

import serial

from devsim.devices.gms96.codec import (
    ACD,
    ACK,
    DFC,
    Frame,
    FrameDecoder,
    FrameError,
    LongFrame,
    ShortFrame,
    SingleChar,
    control_host,
    encode,
    letter,
    short_command,
    short_extension_host,
)

__all__ = ["Gms96Client", "Gms96Error", "Gms96NoData", "Gms96ReplyError", "Gms96Timeout"]

_POLL = 0.02


class Gms96Error(Exception):
    """Base class of the client's errors (spec §3.7)."""


class Gms96Timeout(Gms96Error):
    """The card did not answer (no valid frame) within the client's timeout (spec §3.4)."""


class Gms96ReplyError(Gms96Error):
    """The card answered with a frame of an unexpected type (spec §3.7)."""


class Gms96NoData(Gms96ReplyError):
    """The card answered a ``T`` request with E5h: no data for this P1/P2 (spec §3.7)."""


def t_param_count(p1: int, p2: int, p3: int) -> int:
    """How many parameters a ``T`` request carries, as in the spec's vectors (§3.11):
    ``T0`` one, ``T1;1|2|3|6;P3`` and anything with P3 ≠ 0 three, all others two."""
    if p3 or (p1 == 1 and p2 in (1, 2, 3, 6)):
        return 3
    if p1 == 0 and p2 == 0:
        return 1
    return 2


class Gms96Client:
    """Host side of one GMS96 card at ``address`` on ``port`` (the primary station, spec §3.4)."""

    def __init__(
        self, port: serial.SerialBase, address: int, *, e_version: bool = False, timeout: float = 0.5
    ) -> None:
        if not 0 <= address <= 0xFF:
            raise ValueError(f"address must be 0..255, not {address}")
        self.port = port
        self.address = address
        self.e_version = e_version
        self.timeout = timeout
        # The reply ends by structure; be lenient with gaps inside it (a paced or virtual-time
        # device may deliver a reply slowly).
        self.decoder = FrameDecoder(
            short_extension=short_extension_host, char_timeout=max(0.05, timeout), accept_single=True
        )
        #: FCB of the last FCV=1 frame sent; the first command goes out with FCB = 0 (53h).
        self.fcb = 1
        #: The frames' bytes of the last transmission (what :meth:`repeat_last` sends).
        self.last_sent: bytes | None = None
        #: The reply to the last exchange (``None`` after a timeout).
        self.last_reply: Frame | None = None
        #: Framing errors seen while waiting for the last reply.
        self.errors: list[FrameError] = []
        try:
            port.timeout = min(_POLL, timeout) if timeout > 0 else 0
        except (OSError, termios.error, serial.SerialException):
            # a Linux pty's glibc check fails a repeated request for parity E (EINVAL) after the
            # kernel took it: pyserial keeps the new timeout all the same (docs/connect.md)
            pass

    # -- link ------------------------------------------------------------------------------
    def exchange(self, data: bytes) -> Frame | None:
        """Send raw bytes, return the first valid frame received within ``timeout`` or None.

        Stale input (e.g. a late reply to an earlier exchange) is dropped before sending."""
        self.port.reset_input_buffer()
        self.decoder.reset()
        self.errors = []
        self.last_sent = bytes(data)
        self.port.write(data)
        self.port.flush()
        self.last_reply = self._receive()
        return self.last_reply

    def transact(self, frame: Frame) -> Frame | None:
        """Send one frame and return the reply frame (or None on timeout)."""
        return self.exchange(encode(frame))

    def _receive(self) -> Frame | None:
        deadline = time.monotonic() + self.timeout
        while True:
            chunk = self.port.read(max(1, self.port.in_waiting))
            now = time.monotonic()
            if chunk:
                for item in self.decoder.feed(chunk, now):
                    if isinstance(item, FrameError):
                        self.errors.append(item)
                    else:
                        return item
            if now >= deadline:
                self.errors.extend(self.decoder.expire(float("inf")))
                return None

    # -- letter commands (Langsatz) ----------------------------------------------------------
    def send_letter(self, command: str, *params: int) -> Frame | None:
        """Send a letter command with the next FCB (FCV = 1, FC = 3); returns the reply:
        ``SingleChar(0xE5)``, a ``LongFrame`` for ``T``, or None on timeout."""
        data = letter(command, *params)
        self.fcb ^= 1
        frame = LongFrame(control_host(self.fcb), self.address, data)
        return self.transact(frame)

    def read(
        self, p1: int, p2: int = 0, p3: int = 0, *, nparams: int | None = None
    ) -> tuple[int, int, bytes]:
        """``T P1;P2;P3`` → ``(identifier, value as unsigned little-endian int, raw value)``.

        ``nparams`` overrides how many parameters are sent (default: :func:`t_param_count`).
        Raises :class:`Gms96Timeout`, :class:`Gms96NoData` (E5h) or :class:`Gms96ReplyError`."""
        count = t_param_count(p1, p2, p3) if nparams is None else nparams
        reply = self.send_letter("T", *(p1, p2, p3)[:count])
        if reply is None:
            raise Gms96Timeout(f"no answer to T{p1};{p2};{p3} from address {self.address}")
        if isinstance(reply, SingleChar):
            raise Gms96NoData(f"T{p1};{p2};{p3}: card answered {reply.value:02X}h (no data)")
        if not isinstance(reply, LongFrame) or not reply.data:
            raise Gms96ReplyError(f"unexpected answer to T{p1};{p2};{p3}: {reply!r}")
        value = reply.data[1:]
        return reply.data[0], int.from_bytes(value, "little"), value

    @property
    def acd(self) -> bool:
        """E-version: the last Langsatz reply had ACD set (message waiting, poll #1)."""
        return isinstance(self.last_reply, LongFrame) and bool(self.last_reply.control & ACD)

    @property
    def dfc(self) -> bool:
        """E-version: the last Langsatz reply had DFC set (command queue full)."""
        return isinstance(self.last_reply, LongFrame) and bool(self.last_reply.control & DFC)

    # -- Kurzsatz commands --------------------------------------------------------------------
    def _short(self, number: int, extension: bytes = b"") -> Frame | None:
        return self.transact(short_command(number, self.address, extension))

    def _expect_ack(self, reply: Frame | None, what: str) -> None:
        if reply is None:
            raise Gms96Timeout(f"no answer to {what} from address {self.address}")
        if reply != SingleChar(ACK):
            raise Gms96ReplyError(f"unexpected answer to {what}: {reply!r}")

    def status(self) -> tuple[int, int | None]:
        """#1 Kurzsatz status → ``(K, MB4 or None)`` (M §2.3.2; reading clears MB4)."""
        reply = self._short(1)
        if reply is None:
            raise Gms96Timeout(f"no answer to #1 from address {self.address}")
        if not isinstance(reply, ShortFrame):
            raise Gms96ReplyError(f"unexpected answer to #1: {reply!r}")
        return reply.control, (reply.extension[0] if reply.extension else None)

    def abort(self) -> None:
        """#0 Abbruch: abort the running operation, discard pending commands."""
        self._expect_ack(self._short(0), "#0")

    def spindle_speed(self, value: int) -> None:
        """#8 actual spindle speed for G95: 2 AE octets, low byte first (unsigned 16 bit)."""
        if not 0 <= value <= 0xFFFF:
            raise ValueError(f"spindle speed must be 0..65535, not {value}")
        self._expect_ack(self._short(8, value.to_bytes(2, "little")), "#8")

    def override(self, percent: int) -> None:
        """#9 external override: one AE octet (the card accepts 0..125 %, clamps above)."""
        if not 0 <= percent <= 0xFF:
            raise ValueError(f"override must be 0..255, not {percent}")
        self._expect_ack(self._short(9, bytes([percent])), "#9")

    # -- link services ------------------------------------------------------------------------
    def repeat_last(self) -> Frame | None:
        """Re-send the previous frame unchanged (same FCB) and return the reply: what a host
        does when a reply was lost (spec §3.4 FCB rule)."""
        if self.last_sent is None:
            raise Gms96Error("nothing sent yet")
        return self.exchange(self.last_sent)

    def reset_link(self) -> Frame | None:
        """E-version "reset of remote link": fixed frame ``10 40 A CS 16`` (FC0, FCV=0, FCB=0).

        The card decodes it as #0 (abort, spec §3.6 rule 4), which in the E-version also
        resets its FCB expectation (§3.9); the next command goes out with FCB = 1 as IEC
        60870-5-2 expects.  Refused for an S-version card, which has no link reset and would
        just abort."""
        if not self.e_version:
            raise Gms96Error("reset of remote link is an E-version service (on an S-version card it is #0)")
        reply = self.transact(ShortFrame(control_host(0, fcv=0, fc=0), self.address))
        self.fcb = 0
        return reply
