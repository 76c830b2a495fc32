"""The FT1.2 face of the GMS96 card: link, command dispatch and replies (manual §2.3; spec §3).

The link layer (:mod:`.link`) finds frames, filters addresses, suppresses repetitions and times
replies; this face turns each Kurzsatz and Langsatz into operations on the card
(:class:`~devsim.devices.gms96.model.Gms96Card`) and builds the answers: ``E5h``, the status
Kurzsatz and the ``T`` read-backs.  Every command is looked up in a table that ``devsim doc
gms96`` lists: :data:`SHORT_COMMANDS` (Kurzsatz), :data:`ON_RECEIPT` (the letters the face handles
itself: immediate commands, downloads), :data:`P_ON_RECEIPT` (``p`` downloads, ``p11``),
:data:`T_QUERIES` (``T`` read-backs); every other letter of
:data:`~devsim.devices.gms96.commands.QUEUED_COMMANDS` goes to the command queue.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import lru_cache
from types import MethodType

import msgspec

from devsim.core.device import Face, Port, SerialSettings
from devsim.core.kit import Command, Table
from devsim.devices.gms96 import codec, tables
from devsim.devices.gms96.commands import QUEUED_COMMANDS
from devsim.devices.gms96.executor import Cmd
from devsim.devices.gms96.link import Link, ShortHandler
from devsim.devices.gms96.model import Gms96Card

__all__ = ["ON_RECEIPT", "P_ON_RECEIPT", "SHORT_COMMANDS", "T_QUERIES", "Gms96Face", "Letter"]

ACK = bytes([codec.ACK])


class Letter(msgspec.Struct, frozen=True):
    """A letter command as received (manual §2.3, spec §3.5): letter, P1..P3, the number of
    parameters sent, the raw user data, and where a deferred acknowledgement goes
    (``on_queue_full: defer``)."""

    letter: str
    p1: int
    p2: int
    p3: int
    count: int
    raw: bytes
    deferred: Callable[[bytes], None]


class Gms96Face(Face):
    """One card's end of an RS422/485 line (DIN 19244 FT1.2, 8E1; manual §2.3, spec §3.7)."""

    model: Gms96Card
    #: 8E1 at the DIL switches' rate, read at power-on: a plain attribute, the same object while
    #: the rate stands (the line compares the host's settings with it once, not at every chunk,
    #: and reads it twice per poll)
    serial_settings: SerialSettings = SerialSettings(9600, 8, "E", 1)

    def __init__(self, model: Gms96Card, port: Port) -> None:
        super().__init__(model, port)
        self.link = Link(
            card=model, clock=model.clock, options=model.cfg.link, baud=lambda: int(model.dil.baud),
            errors=model.link_errors, short_handler=self.short_handler, letter_command=self.letter_command,
            write=port.send,
        )
        #: the host's bytes go straight to the link (no call of this face's own on a poll's path)
        self.feed = self.link.feed
        self._k_answers: tuple[bytes, ...] = ()  # the answers to #1 without a message, by status byte
        self._read_dil()
        model.listen("power_on", self._power_on)

    def _power_on(self) -> None:
        """The link starts afresh; the address and the rate may be others (DIL switches)."""
        self.link.reset()
        self._read_dil()

    def _read_dil(self) -> None:
        """What the DIL switches read at power-on set (manual §2.2): the answers to #1 without a
        message for the card's address, by status byte, and the line settings at its rate."""
        model = self.model
        self._k_answers = status_answers(model.address)
        baud = int(model.dil.baud)
        if self.serial_settings.baudrate != baud:
            self.serial_settings = SerialSettings(baud, 8, "E", 1)

    def close(self) -> None:
        self.link.close()

    def feed(self, data: bytes) -> None:
        """The host's bytes to the link (each face has the link's own ``feed`` in its place)."""
        self.link.feed(data)

    def host_disconnected(self) -> None:
        """A partial frame of a host that left is dropped by the character timeout."""

    def short_handler(self, number: int) -> ShortHandler:
        """The handler of Kurzsatz #0, #1, #8, #9 (manual §2.3.2), looked up in
        :data:`SHORT_COMMANDS`; any other number: :meth:`unknown_short`."""
        handler = _SHORT_BY_NUMBER.get(number)
        return self.unknown_short if handler is None else MethodType(handler, self)

    def unknown_short(self, ext: bytes) -> bytes | None:
        """A Kurzsatz number the card does not know: E5h or nothing (``link.unknown_short_command_reply``)."""
        return ACK if self.model.cfg.link.unknown_short_command_reply == "ack" else None

    def letter_command(
        self, cmd: str, params: tuple[int, int, int], count: int, raw: bytes, *, deferred: Callable[[bytes], None]
    ) -> bytes | None:
        """A Langsatz letter command: :data:`ON_RECEIPT`, else the queue (:data:`QUEUED_COMMANDS`)."""
        self.model.record_event(f"cmd_{cmd}")
        letter = Letter(cmd, *params, count, raw, deferred)
        handler = ON_RECEIPT.get(cmd) or (Gms96Face.queue if cmd in QUEUED_COMMANDS else Gms96Face.unknown)
        return handler(self, letter)

    # -- the routes of a letter (spec §4.2.1) ---------------------------------------------------
    def queue(self, letter: Letter) -> bytes | None:
        """A queued command: recorded during a CNC download, else into the queue; a full queue
        drops, refuses or defers the acknowledgement (``link.on_queue_full``)."""
        recorded = self.model.flash.recording("cnc")
        if recorded is not None:
            recorded.append([letter.letter, letter.p1, letter.p2, letter.p3, letter.count])
            return ACK
        item = Cmd(letter.letter, letter.p1, letter.p2, letter.p3, letter.count)
        executor = self.model.executor
        if executor.full:
            mode = self.model.cfg.link.on_queue_full
            if mode == "drop":
                return None
            if mode == "nack":
                return codec.encode(codec.ShortFrame(0x01, self.model.address))
            executor.defer(item, lambda: letter.deferred(ACK))
            return None
        executor.submit(item)
        return ACK

    def unknown(self, letter: Letter) -> bytes | None:
        self.model.record_event("unknown_command")
        return ACK if self.model.cfg.link.unknown_command_reply == "ack" else None

    def download_line(self, letter: Letter) -> bytes | None:
        """``a``: a line of a PLC download (kept opaque); in a CNC download it is recorded like a
        queued command; otherwise ignored."""
        plc = self.model.flash.recording("plc")
        if plc is not None:
            plc.append([letter.raw[1:].hex()])
            return ACK
        if self.model.flash.recording("cnc") is not None:
            return self.queue(letter)
        return ACK

    def override(self, letter: Letter) -> bytes | None:
        """``o2;P2`` on receipt (never recorded); ``o0``/``o1`` queue."""
        if letter.p1 != 2:
            return self.queue(letter)
        m = self.model
        m.feed.set_override_inactive_value(letter.p2)
        m.speed_changed()
        return ACK

    def program(self, letter: Letter) -> bytes | None:
        """``p``: the downloads and ``p11`` on receipt (:data:`P_ON_RECEIPT`), the rest queues."""
        handler = (
            P_ON_RECEIPT.get(f"{letter.p1};{letter.p2}") or P_ON_RECEIPT.get(str(letter.p1)) or Gms96Face.queue
        )
        return handler(self, letter)

    def marker_byte(self, letter: Letter) -> bytes | None:
        """``p11;offset;value``: MB(offset) := value at once (recorded during a CNC download)."""
        if self.model.flash.recording("cnc") is not None:
            return self.queue(letter)
        self.model.write_marker_byte(letter.p2, letter.p3)
        return ACK

    def register(self, letter: Letter) -> bytes | None:
        """``c value;n``: data register R(n)."""
        if 0 <= letter.p2 <= 19:
            self.model.image.write_register(letter.p2, letter.p1)
            self.model.memory.save_static()
        return ACK

    def n_parameter(self, letter: Letter) -> bytes | None:
        """``N value;index;P3``."""
        self.model.set_n(letter.p2, letter.p1, letter.p3)
        return ACK

    def message_query(self, letter: Letter) -> bytes | None:
        """``q``: M3.1, the PLC reports pending messages again."""
        self.model.image.set_marker(3, 1, True)
        self.model.changed()
        return ACK

    # -- downloads (spec §3.8.13, §3.8.24) -----------------------------------------------------
    def _begin_download(self, kind: str, number: int) -> None:
        m = self.model
        if m.flash.download is None:
            if kind == "cnc" and not 0 <= number < m.cfg.max_programs:
                return
            m.flash.download = (kind, number, [])
            if kind == "plc":
                m.plc.begin_download()
            m.silence(m.cfg.flash_erase_s)
            m.record_event("flash_erase")

    def begin_plc_download(self, letter: Letter) -> bytes:
        self._begin_download("plc", letter.p3)
        return ACK

    def begin_cnc_download(self, letter: Letter) -> bytes:
        self._begin_download("cnc", letter.p3)
        return ACK

    def end_plc_download(self, letter: Letter) -> bytes:
        recorded = self.model.flash.recording("plc")
        if recorded is not None:
            self.model.flash.download = None
            self.model.plc.end_download([bytes.fromhex(row[0]) for row in recorded])
        return ACK

    def end_cnc_download(self, letter: Letter) -> bytes:
        flash = self.model.flash
        if flash.download is not None and flash.download[0] == "cnc":
            _kind, pnr, recorded = flash.download
            flash.download = None
            flash.store_program(pnr, recorded, self.model.cfg.max_total_commands)
        return ACK

    # -- T read-backs (manual §2.3.1 T; spec §3.8.19) --------------------------------------------
    def read_back(self, letter: Letter) -> bytes:
        """``T P1;P2;P3``: :data:`T_QUERIES` by ``P1;P2``, then ``P1``; anything else: E5h."""
        p1, p2, p3 = letter.p1, letter.p2, letter.p3
        handler = T_QUERIES.get(f"{p1};{p2}") or T_QUERIES.get(str(p1))
        return ACK if handler is None else handler(self, p2, p3)

    def _reply_control(self) -> int:
        control = 0x08
        if self.model.e_version:
            feats = self.model.cfg.link.e_version_features
            if "acd" in feats and self.model.image.markers[4]:
                control |= codec.ACD
            if "dfc" in feats and self.model.executor.full:
                control |= codec.DFC
        return control

    def _t(self, identifier: int, value: bytes) -> bytes:
        return codec.encode(codec.t_reply(self.model.address, identifier, value, self._reply_control()))

    def t_setpoint(self, p2: int, p3: int) -> bytes:
        return self._t(0x40, codec.to_s24(codec.wrap24(self.model.coordinates.setpoint_work())))

    def t_version(self, p2: int, p3: int) -> bytes:
        return self._t(0x56, tables.FIRMWARE_VERSION.to_bytes(2, "little"))

    def t_inputs(self, p2: int, p3: int) -> bytes:
        return self._t(0x49, bytes([self.model.outputs.input_byte(p3), self.model.outputs.input_byte(p3 + 1)]))

    def t_outputs(self, p2: int, p3: int) -> bytes:
        return self._t(0x49, bytes([self.model.outputs.output_byte(p3), self.model.outputs.output_byte(p3 + 1)]))

    def t_markers(self, p2: int, p3: int) -> bytes:
        m = self.model
        return self._t(0x49, bytes([m.marker_byte(p3) if 0 <= p3 < 256 else 0,
                                    m.marker_byte(p3 + 1) if 0 <= p3 + 1 < 256 else 0]))

    def t_following_error(self, p2: int, p3: int) -> bytes:
        e = int(round(self.model.indexer.following_error()))
        return self._t(0x49, max(-32768, min(32767, e)).to_bytes(2, "little", signed=True))

    def t_current(self, p2: int, p3: int) -> bytes:
        return self._t(0x49, bytes([min(252, int(round(252 * self.model.torque.current())))]))

    def t_data(self, p2: int, p3: int) -> bytes:
        image = self.model.image
        return self._t(0x44, image.read_bytes(image.data, p3, 3))

    def t_status(self, p2: int, p3: int) -> bytes:
        return self._t(self.model.status(), b"")

    def t_memory_status(self, p2: int, p3: int) -> bytes:
        return self._t(self.model.memory_status(), b"")

    def t_n_parameter(self, p2: int, p3: int) -> bytes:
        if p2 not in tables.N_TABLE:
            return ACK
        return self._t(0x4E, codec.to_s24(codec.wrap24(self.model.params.read(p2, p3))))

    # -- Kurzsatz (manual §2.3.2) ----------------------------------------------------------------
    def abort(self, ext: bytes) -> bytes:
        """#0: abort; the queue is flushed, a download ends."""
        m = self.model
        m.record_event("abort")
        m.flash.download = None
        m.spindle.on = False
        m.executor.abort()
        return ACK

    def status_frame(self, ext: bytes) -> bytes:
        """#1: the status Kurzsatz (K byte, and the MB4 message in the address extension)."""
        m = self.model
        status = m.status()
        if not status & _MESSAGE:  # (MB4 is 0: the K byte alone, looked up by the status byte)
            return self._k_answers[status]
        return codec.k_bytes(tables.k_from_status(status, False), m.address, m.image.take_message())

    def spindle_rpm(self, ext: bytes) -> bytes:
        """#8: the spindle speed for G95."""
        self.model.feed.spindle_rpm = int.from_bytes(ext[:2], "little") if len(ext) >= 2 else 0
        self.model.speed_changed()
        return ACK

    def external_override(self, ext: bytes) -> bytes:
        """#9: an override 0..125 % from the host (the potentiometer is ignored from then on)."""
        self.model.feed.ext_override = min(ext[0] if ext else 0, 125)
        self.model.feed.o2_value = None
        self.model.speed_changed()
        return ACK


_MESSAGE = tables.STATUS_BITS["MESSAGE"]


@lru_cache(maxsize=32)
def status_answers(address: int) -> tuple[bytes, ...]:
    """The answer to #1 of a card at ``address`` with no message in MB4, by the status byte of
    ``T3;0`` (spec §4.3.3): ``k_bytes(k_from_status(status, False), address, None)``, made once
    per address and shared by every card there."""
    return tuple(codec.k_bytes(tables.k_from_status(status, False), address, None) for status in range(256))


#: Kurzsatz numbers (manual §2.3.2, spec §3.7).
SHORT_COMMANDS: Table[Callable[[Gms96Face, bytes], bytes]] = Table(
    [
        Command("0", Gms96Face.abort, "§2.3.2", "#0: abort; the queue is flushed, a download ends"),
        Command("1", Gms96Face.status_frame, "§2.3.2", "#1: status Kurzsatz (K byte, MB4 message)"),
        Command("8", Gms96Face.spindle_rpm, "§2.3.2", "#8: spindle speed (G95)"),
        Command("9", Gms96Face.external_override, "§2.3.2", "#9: override 0..125 %"),
    ]
)

#: :data:`SHORT_COMMANDS` by the number itself (a poll looks its handler up without a string).
_SHORT_BY_NUMBER: dict[int, Callable[[Gms96Face, bytes], bytes]] = {int(row.token): row.handler
                                                                    for row in SHORT_COMMANDS}

LetterHandler = Callable[[Gms96Face, Letter], "bytes | None"]

#: Letters the face handles on receipt (spec §4.2.1): the immediate commands, ``o2``, ``p11``, the
#: downloads; every other letter of :data:`QUEUED_COMMANDS` queues.
ON_RECEIPT: Table[LetterHandler] = Table(
    [
        Command("T", Gms96Face.read_back, "§2.3.1 T", "read back position, I/O, markers, status, N (the T rows)"),
        Command("c", Gms96Face.register, "§2.3.1 c", "write a data register"),
        Command("N", Gms96Face.n_parameter, "§2.3.1 N", "write an N parameter"),
        Command("o", Gms96Face.override, "§2.3.1 o", "o2: override value (immediate form); o0/o1 queue"),
        Command("p", Gms96Face.program, "§2.3.1 p", "the downloads and p11 on receipt; the rest queues"),
        Command("q", Gms96Face.message_query, "§2.3.1 q", "acknowledge the message (M3.1)"),
        Command("a", Gms96Face.download_line, "§2.3.1 p", "a: a PLC download line (ignored outside a download)"),
    ]
)

#: ``p`` functions carried out on receipt (spec §3.8.13), by ``P1;P2`` or ``P1``.
P_ON_RECEIPT: Table[LetterHandler] = Table(
    [
        Command("1;100", Gms96Face.begin_plc_download, "§2.3.1 p", "begin a PLC download (flash erase: silent)"),
        Command("1;101", Gms96Face.end_plc_download, "§2.3.1 p", "end of the PLC download"),
        Command("3;100", Gms96Face.begin_cnc_download, "§2.3.1 p", "begin the download of CNC program P3 (silent)"),
        Command("3;101", Gms96Face.end_cnc_download, "§2.3.1 p", "end of the CNC download (program 0: all anew)"),
        Command("11", Gms96Face.marker_byte, "§2.3.1 p", "MB(P2) := P3 at once (recorded in a CNC download)"),
    ]
)

#: ``T P1;P2;P3`` read-backs (manual §2.3.1 T, spec §3.8.19), by ``P1;P2`` or ``P1``.
T_QUERIES: Table[Callable[[Gms96Face, int, int], bytes]] = Table(
    [
        Command("0", Gms96Face.t_setpoint, "§2.3.1 T", "T0: set-point position (work frame)"),
        Command("1;0", Gms96Face.t_version, "§2.3.1 T", "T1;0: software version × 100"),
        Command("1;1", Gms96Face.t_inputs, "§2.3.1 T", "T1;1;P3: inputs EB(P3), EB(P3+1)"),
        Command("1;2", Gms96Face.t_outputs, "§2.3.1 T", "T1;2;P3: outputs AB(P3), AB(P3+1)"),
        Command("1;3", Gms96Face.t_markers, "§2.3.1 T", "T1;3;P3: markers MB(P3), MB(P3+1)"),
        Command("1;4", Gms96Face.t_following_error, "§2.3.1 T", "T1;4: following error"),
        Command("1;5", Gms96Face.t_current, "§2.3.1 T", "T1;5: motor current (252 = Imax)"),
        Command("1;6", Gms96Face.t_data, "§2.3.1 T", "T1;6;P3: 3 data bytes from P3"),
        Command("3;0", Gms96Face.t_status, "§2.3.1 T", "T3;0: standard status"),
        Command("3;4", Gms96Face.t_memory_status, "§2.3.1 T", "T3;4: memory status"),
        Command("5", Gms96Face.t_n_parameter, "§2.3.1 T", "T5;n;P3: N parameter n (N8: P3 = 1 the upper limit)"),
    ]
)
