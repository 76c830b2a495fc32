"""The FT1.2 face of the GMS96 card: link, command dispatch and replies (manual §2.3; spec §3).

The link layer (:mod:`.link`) finds frames, filters addresses, suppresses repetitions and times
replies; this face turns each Kurzsatz and Langsatz into operations on the card
(:class:`~devsim.devices.gms96.card.Gms96Card`) and builds the answers: ``E5h``, the status
Kurzsatz and the ``T`` read-backs.  Commands are looked up in tables (:data:`SHORT_COMMANDS`,
:data:`IMMEDIATE_COMMANDS`, :data:`QUEUED_COMMANDS`) that ``devsim doc gms96`` lists.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from devsim.core.device import Face, Port, SerialSettings
from devsim.core.kit import Command, Table
from devsim.devices.gms96 import codec, tables
from devsim.devices.gms96.card import Gms96Card, _wrap24
from devsim.devices.gms96.executor import Cmd
from devsim.devices.gms96.link import Link

__all__ = ["IMMEDIATE_COMMANDS", "QUEUED_COMMANDS", "SHORT_COMMANDS", "Gms96Face"]

ACK = bytes([codec.ACK])
ON_RECEIPT = frozenset("cNqT")  # always immediate; o only as o2, p only as p11 (spec §4.2.1)


class Gms96Face(Face):
    """One card's end of an RS422/485 line (DIN 19244 FT1.2, 8E1)."""

    model: Gms96Card

    def __init__(self, model: Gms96Card, port: Port) -> None:
        super().__init__(model, port)
        self.link = Link(model, self.short_command, self.letter_command, port.send)
        model.listen("power_on", self.link.reset)

    @property
    def serial_settings(self) -> SerialSettings:
        return SerialSettings(self.model.dil.baud, 8, "E", 1)

    def close(self) -> None:
        self.link.close()

    def feed(self, data: bytes) -> None:
        self.link.feed(data)

    def host_disconnected(self) -> None:
        """A partial frame of a host that left is dropped by the character timeout."""

    def short_command(self, number: int, ext: bytes) -> bytes | None:
        """Kurzsatz #0, #1, #8, #9 (manual §2.3.2), looked up in :data:`SHORT_COMMANDS`."""
        handler = SHORT_COMMANDS.get(str(number))
        if handler is None:
            return ACK if self.model.cfg.link.unknown_short_command_reply == "ack" else None
        return handler(self.model, ext)

    def letter_command(
        self, cmd: str, params: tuple[int, int, int], count: int, raw: bytes, *, deferred: Callable[[bytes], None]
    ) -> bytes | None:
        p1, p2, p3 = params
        self.model.record_event(f"cmd_{cmd}")
        if cmd == "p" and p1 in (1, 3) and p2 in (100, 101):
            return self._download_control(p1, p2, p3)
        if self.model.download is not None:
            kind, pnr, recorded = self.model.download
            if kind == "plc" and cmd == "a":
                recorded.append([raw[1:].hex()])
                return ACK
            if kind == "cnc" and (cmd in QUEUED_COMMANDS or (cmd == "p" and p1 == 11)) and not (cmd == "o" and p1 == 2):
                recorded.append([cmd, p1, p2, p3, count])
                return ACK
        if cmd in ON_RECEIPT or (cmd == "o" and p1 == 2) or (cmd == "p" and p1 == 11):
            return self._immediate(cmd, p1, p2, p3)
        if cmd == "a":
            return ACK  # outside a PLC download: ignored
        if cmd in QUEUED_COMMANDS:
            item = Cmd(cmd, p1, p2, p3, count)
            if self.model.executor.full:
                mode = self.model.cfg.link.on_queue_full
                if mode == "drop":
                    return None
                if mode == "nack":
                    return codec.encode(codec.ShortFrame(0x01, self.model.address))
                self.model.executor.defer(item, lambda: deferred(ACK))
                return None
            self.model.executor.submit(item)
            return ACK
        self.model.record_event("unknown_command")
        return ACK if self.model.cfg.link.unknown_command_reply == "ack" else None

    def _download_control(self, p1: int, p2: int, p3: int) -> bytes:
        if p2 == 100:
            if self.model.download is None:
                if p1 == 3 and not 0 <= p3 < self.model.cfg.max_programs:
                    return ACK
                self.model.download = ("cnc" if p1 == 3 else "plc", p3, [])
                if p1 == 1:
                    self.model.plc.begin_download()
                self.model.silence(self.model.cfg.flash_erase_s)
                self.model.record_event("flash_erase")
            return ACK
        if self.model.download is not None and self.model.download[0] == ("cnc" if p1 == 3 else "plc"):
            kind, pnr, recorded = self.model.download
            self.model.download = None
            if kind == "cnc":
                total = sum(len(p) for k, p in self.model.programs.items() if k != pnr) + len(recorded)
                if total > self.model.cfg.max_total_commands:
                    self.model.cnc_storage_error = True
                    return ACK
                if pnr == 0:
                    self.model.programs = {}
                self.model.programs[pnr] = recorded
            else:
                self.model.plc.end_download([bytes.fromhex(row[0]) for row in recorded])
                return ACK
            self.model.save_flash()
        return ACK

    def _immediate(self, cmd: str, p1: int, p2: int, p3: int) -> bytes | None:
        """Commands carried out on receipt (manual §2.3.1, spec §4.2.1): :data:`IMMEDIATE_COMMANDS`."""
        if cmd == "T":
            return self._read_back(p1, p2, p3)
        handler = IMMEDIATE_COMMANDS.get(cmd)
        if handler is not None:
            handler(self.model, p1, p2, p3)
        return ACK

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

    def _read_back(self, p1: int, p2: int, p3: int) -> bytes:
        """``T`` (manual §2.3.1 T; spec §3.8.19)."""
        if p1 == 0:
            return self._t(0x40, codec.to_s24(_wrap24(self.model.setpoint_work())))
        if p1 == 1:
            if p2 == 0:
                return self._t(0x56, tables.FIRMWARE_VERSION.to_bytes(2, "little"))
            if p2 == 1:
                return self._t(0x49, bytes([self.model.input_byte(p3), self.model.input_byte(p3 + 1)]))
            if p2 == 2:
                return self._t(0x49, bytes([self.model.output_byte(p3), self.model.output_byte(p3 + 1)]))
            if p2 == 3:
                return self._t(0x49, bytes([self.model.marker_byte(p3) if 0 <= p3 < 256 else 0,
                                            self.model.marker_byte(p3 + 1) if 0 <= p3 + 1 < 256 else 0]))
            if p2 == 4:
                e = int(round(self.model.indexer.following_error()))
                return self._t(0x49, max(-32768, min(32767, e)).to_bytes(2, "little", signed=True))
            if p2 == 5:
                return self._t(0x49, bytes([min(252, int(round(252 * self.model.current())))]))
            if p2 == 6:
                return self._t(0x44, self.model.image.read_bytes(self.model.image.data, p3, 3))
        if p1 == 3 and p2 == 0:
            return self._t(self.model.status(), b"")
        if p1 == 3 and p2 == 4:
            return self._t(self.model.memory_status(), b"")
        if p1 == 5 and p2 in tables.N_PARAMETERS:
            value = self.model.params.read(p2, p3)
            return self._t(0x4E, codec.to_s24(_wrap24(value)))
        return ACK


# -- the command tables ---------------------------------------------------------------------------
def _status(card: Any, ext: bytes) -> bytes:
    k = tables.k_from_status(card.status(), False)
    return codec.encode(codec.k_frame(k, card.address, card.image.take_message()))


def _abort(card: Any, ext: bytes) -> bytes:
    card.record_event("abort")
    card.download = None
    card.spindle_on = False
    card.executor.abort()
    return ACK


def _spindle_rpm(card: Any, ext: bytes) -> bytes:
    card.spindle_rpm = int.from_bytes(ext[:2], "little") if len(ext) >= 2 else 0
    card.indexer.replan()
    return ACK


def _override(card: Any, ext: bytes) -> bytes:
    card.ext_override = min(ext[0] if ext else 0, 125)
    card.o2_value = None
    card.indexer.replan()
    return ACK


#: Kurzsatz numbers (manual §2.3.2, spec §3.7).
SHORT_COMMANDS: Table[Callable[[Any, bytes], bytes]] = Table(
    [
        Command("0", _abort, "§2.3.2", "#0: abort; the queue is flushed, a download ends"),
        Command("1", _status, "§2.3.2", "#1: status Kurzsatz (K byte, MB4 message)"),
        Command("8", _spindle_rpm, "§2.3.2", "#8: spindle speed (G95)"),
        Command("9", _override, "§2.3.2", "#9: override 0..125 %"),
    ]
)


def _register(card: Any, p1: int, p2: int, p3: int) -> None:
    if 0 <= p2 <= 19:
        card.image.write_register(p2, p1)
        card.save_static()


def _override_o2(card: Any, p1: int, p2: int, p3: int) -> None:
    card.o2_value = max(0, min(100, p2))
    card.ext_override = None
    card.indexer.replan()


def _quit_message(card: Any, p1: int, p2: int, p3: int) -> None:
    card.image.set_marker(3, 1, True)
    card.changed()


#: Letter commands carried out on receipt (``o2``, ``p11`` too), the rest queue (spec §4.2.1).
IMMEDIATE_COMMANDS: Table[Callable[[Any, int, int, int], None]] = Table(
    [
        Command("T", lambda card, p1, p2, p3: None, "§2.3.1 T", "read back position, I/O, markers, status, N"),
        Command("c", _register, "§2.3.1 c", "write a data register"),
        Command("N", lambda card, p1, p2, p3: card.set_n(p2, p1, p3), "§2.3.1 N", "write an N parameter"),
        Command("o", _override_o2, "§2.3.1 o", "o2: override value (immediate form)"),
        Command("p", lambda card, p1, p2, p3: card.write_marker_byte(p2, p3), "§2.3.1 p", "write a marker byte"),
        Command("q", _quit_message, "§2.3.1 q", "acknowledge the message (M3.1)"),
    ]
)

#: Letter commands the executor carries out in order (spec §4.2.1, §3.8).
QUEUED_COMMANDS: Table[str] = Table(
    [
        Command("A", "move", "§2.3.1 A", "absolute move"),
        Command("B", "setting", "§2.3.1 B", "acceleration"),
        Command("d", "setting", "§2.3.1 d", "write a data word"),
        Command("f", "setting", "§2.3.1 f", "feed rate"),
        Command("G", "setting", "§2.3.1 G", "G functions (G53-G57 offsets, G90/91, G92, G94/95)"),
        Command("H", "function", "§2.3.1 H", "H functions (in-position, torque abort, measurement ...)"),
        Command("M", "setting", "§2.3.1 M", "maximum speed"),
        Command("m", "function", "§2.3.1 m", "M functions (outputs, electronic gear m49 ...)"),
        Command("O", "setting", "§2.3.1 O", "set the origin (actual position := value)"),
        Command("o", "setting", "§2.3.1 o", "override on/off"),
        Command("Q", "reference", "§2.3.1 Q", "reference run Q0/1/2/3/6/8/-1"),
        Command("r", "setting", "§2.3.1 r", "defaults (r0) / erase the EEPROM (r1)"),
        Command("S", "setting", "§2.3.1 S", "S function"),
        Command("s", "function", "§2.3.1 s", "save to the EEPROM (s85;170)"),
        Command("v", "move", "§2.3.1 v", "velocity mode (jog)"),
        Command("w", "function", "§2.3.1 w", "wait"),
        Command("+", "move", "§2.3.1 +", "relative move"),
        Command("p", "function", "§2.3.1 p", "program and PLC control (p1, p3)"),
        Command("a", "function", "§2.3.1 a", "a PLC download line"),
    ]
)
