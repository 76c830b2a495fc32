"""The card's side of the DIN 19244 link (manual §2.1, §2.3, §2.3.2; spec §3.2–§3.10).

Frames are found by structure (:class:`~devsim.devices.gms96.codec.FrameDecoder`); the
inter-character timeout only discards a stale partial frame (a clock timer, so virtual time
works).  Frames with a bad checksum, length or end byte, and frames for another address, get
no reply.  E-version (DIL 7 on, spec §3.9): a Langsatz with FCV = 1 and the same FCB as the last
accepted one is a repetition — the previous reply is sent again byte-identically and nothing is
executed; #0, power-on and a reset-of-remote-link frame (FC0, FCV = 0) make the FCB state
"unknown".  The card is silent during its boot time and during the flash erase after
``p1;100`` / ``p3;100`` (manual §2.3.1 p).

FT1.2 rule R4 (spec §3.2, §3.10; config ``link.error_line_idle``, default on): after a detected
error (checksum, length, start/end byte, garbage outside a frame — what a parity or framing
error leaves) the card accepts a new frame only after at least 33 bit times (at the DIL baud
rate) of line idle, measured on the device clock from the last byte received.  [SIM-CHOICE] When
the card has answered since that byte, a frame comes no earlier than the end of the answer on
the line (response delay + 11 bit times per character at the DIL baud rate): the host hears the
whole answer before it sends again (half duplex, spec §3.4), which a pty's instant answer would
otherwise hide.  Everything
arriving earlier — the rest of the chunk that held the error, and chunks back-to-back behind
it — is discarded without reply, and each such byte restarts the idle interval.  A partial frame
dropped by the inter-character timeout arms nothing: the line has already been idle for the
timeout.

A host's poll is the same few bytes again and again: a chunk that was one whole Kurzsatz to this
card is remembered, and when it comes again between frames (nothing pending, no error held, the
card listening) it is answered in one step, without the decoder (what it would find is known).
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Protocol

from devsim.core.clock import Clock, Timer
from devsim.core.settings import Settings
from devsim.devices.gms96 import codec


class LinkCard(Protocol):
    """What the link asks of its card (manual §2.2, §2.3): its address and protocol version (DIL switch, read at
    power-on), whether it listens (and until when it is silent, and whether it is powered), and an event for
    the log."""

    @property
    def address(self) -> int: ...
    @property
    def e_version(self) -> bool: ...
    @property
    def silent(self) -> bool: ...
    @property
    def silent_until(self) -> float: ...
    @property
    def powered(self) -> bool: ...
    def silent_at(self, now: float) -> bool: ...
    def record_event(self, name: str) -> None: ...


__all__ = ["Link", "NO_REPLY", "ShortHandler"]

#: What a Kurzsatz command does with its AE octets; returns the reply (``None``: no reply).
ShortHandler = Callable[[bytes], "bytes | None"]

NO_REPLY = b""
IDLE_BITS = 33  #: FT1.2 R4 minimum line idle after an error, in bit times
CHAR_BITS = 11  #: one 8E1 character on the line: start, 8 data, parity, stop (manual §2.1)
_POLLS = 16  #: distinct whole-Kurzsatz chunks a link remembers (a host polls with a few)


class Link:
    """Decoder, address filter, duplicate suppression, reply timing (manual §2.3; spec §3.2-§3.10)."""

    def __init__(
        self,
        *,
        card: LinkCard,
        clock: Clock,
        options: Settings,
        baud: Callable[[], int],
        errors: dict[str, int],
        short_handler: Callable[[int], ShortHandler],
        letter_command: Callable[..., bytes | None],
        write: Callable[[bytes], None],
    ) -> None:
        self.card = card
        self.clock = clock
        self.options = options  # the configuration's ``link:``
        self.baud = baud  # the DIL switch's baud rate
        self.short_handler = short_handler  # the handler of Kurzsatz #number
        self.letter_command = letter_command
        self.write = write
        self.decoder = codec.FrameDecoder(
            short_extension=codec.short_extension_device, char_timeout=options.char_timeout
        )
        self.last_fcb: int | None = None
        self.last_reply = NO_REPLY
        self.accepted = 0  # E-version frames with FCV accepted: whose reply ``last_reply`` is
        self.errors = errors
        self.frames = 0
        self._expire: Timer | None = None
        self.error_hold = False  # R4: an error was detected, waiting for line idle
        self._last_byte = float("-inf")
        #: when the card's last answer was sent and when it ends on the line (device clock)
        self._answered_at = float("-inf")
        self._answer_end = float("-inf")
        #: chunks that were one whole Kurzsatz to this card, with its command number, AE octets
        #: and handler: a host's poll, the same bytes again and again, answered in one step
        #: (forgotten at power-on, which may bring another address); at most :data:`_POLLS` of them
        self._polls: dict[bytes, tuple[int, bytes, ShortHandler]] = {}
        #: a clock reading at which the card listened: a card whose silence ended by then still
        #: listens (time only moves forward), so a poll need not read the clock to know it
        self._listened_at = float("-inf")

    @property
    def idle_after_error(self) -> float:
        """R4 minimum line idle in seconds: 33 bit times at the DIL baud rate."""
        return IDLE_BITS / self.baud()

    def reset(self) -> None:
        self.decoder.reset()
        self._polls.clear()
        self.error_hold = False
        self.last_fcb = None
        self.last_reply = NO_REPLY

    @property
    def silent(self) -> bool:
        return self.card.silent

    def close(self) -> None:
        if self._expire is not None:
            self._expire.cancel()
            self._expire = None

    # -- input ----------------------------------------------------------------------------------
    def feed(self, data: bytes) -> None:
        poll = self._polls.get(data) if type(data) is bytes else None
        if poll is not None and not self.error_hold and not self.decoder.partial:
            card = self.card
            if card.silent_until <= self._listened_at and card.powered:
                # a whole Kurzsatz to this card between frames, as before: what the decoder and
                # _short would make of it, without looking again (nothing pending, no error held)
                self._short_command(*poll)
                return
        now = self.clock.now()
        if self.card.silent_at(now):
            self.decoder.reset()  # the frame is lost
            return
        self._listened_at = now
        if self.error_hold and data:
            # an answer sent since the error: the host heard all of it first (R4, [SIM-CHOICE])
            start = max(now, self._answer_end) if self._answered_at >= self._last_byte else now
            if start - self._last_byte < self.idle_after_error:
                self._last_byte = now  # the line is not idle: the bytes are lost (R4)
                self.decoder.reset()
                self._count("not_idle")
                return
            self.error_hold = False
        if data:
            self._last_byte = now
        whole = not self.decoder.partial
        items = self.decoder.feed(data, now)
        if len(items) == 1 and type(items[0]) is codec.ShortFrame:
            frame = items[0]  # a whole Kurzsatz (a poll): the card listens, as just asked
            if whole and not self.decoder.partial and frame.address == self.card.address:
                number = codec.short_command_number(frame.control)
                poll = number, frame.extension, self.short_handler(number)
                if len(self._polls) < _POLLS:
                    self._polls[bytes(data)] = poll
                self._short_command(*poll)
            else:
                self._short(frame)
        else:
            for item in items:
                if self.error_hold and not isinstance(item, codec.FrameError):
                    self._count("not_idle")  # back-to-back behind an error in the same chunk (R4)
                    continue
                self._handle(item)
        if self.error_hold:
            self.decoder.reset()  # a partial frame that began behind the error
        if self._expire is not None:
            self._expire.cancel()
            self._expire = None
        if self.decoder.pending:
            timeout = self.decoder.char_timeout
            self._expire = self.clock.call_later(timeout * 1.0001, self._on_expire)

    def _on_expire(self) -> None:
        self._expire = None
        for item in self.decoder.expire(self.clock.now()):
            self._handle(item)

    def _handle(self, item: codec.Frame | codec.FrameError) -> None:
        if isinstance(item, codec.FrameError):
            self._count(item.reason)
            if item.reason != "timeout" and self.options.error_line_idle:
                self.error_hold = True
            return
        if self.card.silent:
            return
        if isinstance(item, codec.ShortFrame):
            self._short(item)
        elif isinstance(item, codec.LongFrame):
            self._long(item)

    def _count(self, reason: str) -> None:
        self.errors[reason] = self.errors.get(reason, 0) + 1

    def _mine(self, address: int) -> bool | None:
        """True: addressed to this card; None: broadcast; False: someone else's."""
        if address == self.card.address:
            return True
        bc = self.options.broadcast_address
        return None if bc is not None and address == bc else False

    def _short(self, frame: codec.ShortFrame) -> None:
        if frame.address != self.card.address:
            return  # (a Kurzsatz to the broadcast address is not answered either)
        number = codec.short_command_number(frame.control)
        self._short_command(number, frame.extension, self.short_handler(number))

    def _short_command(self, number: int, extension: bytes, handler: ShortHandler) -> None:
        """Kurzsatz #``number`` to this card (manual §2.3.2): #0 makes the FCB state unknown."""
        self.frames += 1
        if number == 0 and self.card.e_version:
            self.last_fcb = None
        self.send(handler(extension))

    def _long(self, frame: codec.LongFrame) -> None:
        mine = self._mine(frame.address)
        if mine is False:
            return
        parsed = codec.parse_letter(frame.data)
        if parsed is None:
            self._count("parameters")
            return
        self.frames += 1
        control = frame.control
        fcv, fcb = bool(control & codec.FCV), 1 if control & codec.FCB else 0
        check = self.card.e_version and "fcb" in self.options.e_version_features and mine
        if check:
            if not fcv and (control & 0x0F) == 0:
                self.last_fcb = None
            elif fcv:
                if self.last_fcb is not None and fcb == self.last_fcb:
                    self.card.record_event("duplicate")
                    self.send(self.last_reply)
                    return
                self.last_fcb = fcb
        cmd, params, count = parsed
        if not mine:
            deferred: Callable[[bytes], None] = _no_reply
        elif check and fcv:
            self.accepted += 1
            deferred = functools.partial(self._deferred_reply, self.accepted)
        else:
            deferred = self.send
        reply = self.letter_command(cmd, params, count, frame.data, deferred=deferred)
        if mine is None:
            return  # broadcast: executed, never answered (not even a deferred E5h)
        if check and fcv:
            self.last_reply = reply if reply is not None else NO_REPLY
        if reply is not None:
            self.send(reply)

    def _deferred_reply(self, frame: int, reply: bytes) -> None:
        """The E5h of the E-version's ``frame``-th frame with FCV, queued and released when a queue
        slot frees (on_queue_full: defer): the reply a repetition gets, unless the host has sent
        another frame with FCV since (spec §3.9: the previous reply, byte for byte)."""
        if frame == self.accepted:
            self.last_reply = reply
        self.send(reply)

    # -- output ---------------------------------------------------------------------------------
    def send(self, data: bytes | None) -> None:
        if not data:
            return
        delay = self.options.response_delay
        self._answered_at = now = self.clock.now()
        self._answer_end = now + max(delay, 0) + len(data) * CHAR_BITS / self.baud()
        if delay > 0:
            self.clock.call_later(delay, lambda: self.write(data))
        else:
            self.write(data)


def _no_reply(reply: bytes) -> None:
    """The deferred E5h of a broadcast command: dropped (broadcasts are never answered)."""
