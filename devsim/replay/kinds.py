"""What record and replay know of each kind's protocol: framing, decoding, tolerances.

One table, :data:`PROTOCOLS` (kind → :class:`Protocol`); a kind that is not in it is recorded
and replayed byte-exact, with host messages cut where the device starts answering.

* ``split(buffer)`` cuts the bytes a host sent into complete messages and the incomplete rest
  (SERS: a line ends at CR or LF, manual §4.1; GMS96: FT1.2 frames by structure, spec §3.2,
  with :class:`devsim.devices.gms96.codec.FrameDecoder` on the card side).  ``None``: no framing.
* ``decoder(direction)`` makes a stateful per-direction decoder for the session file's
  ``decoded`` field: fed each chunk, it returns the JSON-able descriptions of the messages the
  chunk completes.
* ``tolerances``: the ways a host's request may differ from the recorded one and still be the
  same request, tried in order after an exact match failed.  Each maps a message to a key;
  two messages match under a tolerance when their keys are equal.  A tolerance may also
  ``adapt`` the recorded answer to the host's request (an Ether-S-Bus reply carries the
  request's sequence number).

The table is keyed by kind, or by ``KIND.PORT`` for one port of a kind with several:

| key | host messages | tolerances |
|---|---|---|
| ``sers`` | ASCII lines (CR or LF) | none (exact: the answer echoes the line as typed) |
| ``gms96`` | FT1.2 frames | ``checksum``: the CS octet ignored; ``fcb``: the frame count bit (FCB, 20h of C) and with it the checksum ignored (spec §3.3: a host toggles FCB per frame) |
| ``pcd4h3.ether_tcp`` | Ether-S-Bus frames (by their length field, pcd4h3 spec §9.3) | ``sequence``: another sequence number (and so CRC); the answer gets the host's sequence number and a new CRC |
| others | cut where the device answers | none (exact) |
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from devsim.devices.gms96 import codec as ft12
from devsim.devices.pcd4h3 import sbus

__all__ = ["Decoder", "Protocol", "Tolerance", "protocol_of", "PROTOCOLS"]

Splitter = Callable[[bytes], tuple[list[bytes], bytes]]


class Decoder:
    """Stateful decoder of one direction; the default knows no protocol (decodes nothing)."""

    def __init__(self, direction: str = "host") -> None:
        self.direction = direction

    def feed(self, data: bytes) -> list[Any] | None:
        return None


@dataclass(frozen=True)
class Tolerance:
    """A named way two requests count as the same: ``key(message)`` equal; ``adapt(request,
    answer)`` makes the recorded answer fit the host's request (``None``: sent as recorded)."""

    name: str
    key: Callable[[bytes], bytes]
    adapt: Callable[[bytes, bytes], bytes] | None = None


@dataclass(frozen=True)
class Protocol:
    split: Splitter | None = None
    decoder: Callable[[str], Decoder] = Decoder
    tolerances: tuple[Tolerance, ...] = field(default_factory=tuple)


# -- SERS: ASCII lines ------------------------------------------------------------------------
def _split_at(buffer: bytes, ends: tuple[int, ...]) -> tuple[list[bytes], bytes]:
    """Messages that end after one of the ``ends`` bytes, and the unfinished rest."""
    out: list[bytes] = []
    start = 0
    for i, byte in enumerate(buffer):
        if byte in ends:
            out.append(buffer[start : i + 1])
            start = i + 1
    return out, buffer[start:]


def _split_lines(buffer: bytes) -> tuple[list[bytes], bytes]:
    """Messages end after CR or LF (a CR/LF pair gives a second, one-byte message)."""
    return _split_at(buffer, (0x0D, 0x0A))


class _LineDecoder(Decoder):
    """Text lines (latin-1), each ending after a CR: ``"#P11?\\r"``, ``"\\nok1\\n\\r"``."""

    def __init__(self, direction: str) -> None:
        super().__init__(direction)
        self._rest = b""
        self._ends = (0x0D, 0x0A) if direction == "host" else (0x0D,)

    def feed(self, data: bytes) -> list[Any] | None:
        lines, self._rest = _split_at(self._rest + data, self._ends)
        return [line.decode("latin-1") for line in lines]


# -- GMS96: FT1.2 frames ----------------------------------------------------------------------
def _ft12_card_decoder() -> ft12.FrameDecoder:
    return ft12.FrameDecoder(short_extension=ft12.short_extension_device)


def _split_frames(buffer: bytes) -> tuple[list[bytes], bytes]:
    decoder = _ft12_card_decoder()
    out: list[bytes] = []
    for item in decoder.feed(buffer, 0.0):
        out.append(item.discarded if isinstance(item, ft12.FrameError) else ft12.encode(item))
    return out, buffer[len(buffer) - decoder.pending :] if decoder.pending else b""


def _describe_frame(item: object, from_host: bool) -> dict[str, Any]:
    if isinstance(item, ft12.FrameError):
        return {"error": item.reason, "hex": item.discarded.hex(" ")}
    if isinstance(item, ft12.SingleChar):
        return {"frame": "single", "value": f"{item.value:02X}"}
    if isinstance(item, ft12.ShortFrame):
        described: dict[str, Any] = {"frame": "short", "C": f"{item.control:02X}", "A": item.address}
        if item.extension:
            described["AE"] = item.extension.hex(" ")
        if from_host:  # a Kurzsatz command #0, #1, #8, #9 (spec §3.6)
            described["command"] = f"#{ft12.short_command_number(item.control)}"
        return described
    assert isinstance(item, ft12.LongFrame)
    described = {"frame": "long", "C": f"{item.control:02X}", "A": item.address, "data": item.data.hex(" ")}
    parsed = ft12.parse_letter(item.data) if from_host else None
    if parsed is not None:
        command, params, count = parsed
        described.update(letter=command, params=list(params[:count]), fcb=1 if item.control & ft12.FCB else 0)
    return described


class _FrameDecoder(Decoder):
    def __init__(self, direction: str) -> None:
        super().__init__(direction)
        self._from_host = direction == "host"
        if direction == "host":  # what the card receives
            self._decoder = _ft12_card_decoder()
        else:  # what the host receives: E5h and the K answer's AE octet
            self._decoder = ft12.FrameDecoder(short_extension=ft12.short_extension_host, accept_single=True)

    def feed(self, data: bytes) -> list[Any] | None:
        # frames by structure only: the recorder's timing must not cut a frame (a time of 0)
        return [_describe_frame(item, self._from_host) for item in self._decoder.feed(data, 0.0)]


def _frame_parts(message: bytes) -> tuple[int, int] | None:
    """(index of C, index of CS) of a complete Kurzsatz or Langsatz, else ``None``."""
    if len(message) >= 5 and message[0] == ft12.START_SHORT and message[-1] == ft12.END:
        return 1, len(message) - 2
    if len(message) >= 8 and message[0] == ft12.START_LONG and message[3] == ft12.START_LONG and message[-1] == ft12.END:
        return 4, len(message) - 2
    return None


def _without_checksum(message: bytes) -> bytes:
    parts = _frame_parts(message)
    if parts is None:
        return message
    out = bytearray(message)
    out[parts[1]] = 0
    return bytes(out)


def _without_fcb(message: bytes) -> bytes:
    parts = _frame_parts(message)
    if parts is None:
        return message
    out = bytearray(message)
    out[parts[0]] &= ~ft12.FCB & 0xFF
    out[parts[1]] = 0
    return bytes(out)


# -- PCD4.H3 Ether-S-Bus on TCP: frames with a sequence number ---------------------------------
_ETHER_HEADER = 9  # length (4), version, type, sequence (2), attribute


def _split_ether(buffer: bytes) -> tuple[list[bytes], bytes]:
    receiver = sbus.EtherReceiver()
    frames = receiver.feed(buffer)
    rest = buffer[sum(len(frame) for frame in frames) :]
    if len(rest) >= 4 and not sbus.ether_length_ok(int.from_bytes(rest[:4], "big")):
        return [*frames, rest], b""  # not a frame: one message, so that it is reported
    return frames, rest


class _EtherDecoder(Decoder):
    _ATTRIBUTES = {sbus.REQUEST: "request", sbus.RESPONSE: "response", sbus.ACK_NAK: "ack/nak"}

    def __init__(self, direction: str) -> None:
        super().__init__(direction)
        self._receiver = sbus.EtherReceiver()

    def feed(self, data: bytes) -> list[Any] | None:
        out: list[Any] = []
        for frame in self._receiver.feed(data):
            sequence, attribute = int.from_bytes(frame[6:8], "big"), frame[8]
            payload = frame[_ETHER_HEADER:-2]
            described: dict[str, Any] = {"sequence": sequence, "attribute": self._ATTRIBUTES.get(attribute, attribute),
                                         "payload": payload.hex(" ")}
            if attribute == sbus.REQUEST and len(payload) >= 2:
                described.update(station=payload[0], command=f"{payload[1]:02X}")
            described["crc_ok"] = sbus.crc16(frame[:-2]) == int.from_bytes(frame[-2:], "big")
            out.append(described)
        return out


def _is_ether(frame: bytes) -> bool:
    return len(frame) >= sbus.ETHER_MIN and int.from_bytes(frame[:4], "big") == len(frame)


def _without_sequence(frame: bytes) -> bytes:
    if not _is_ether(frame):
        return frame
    return frame[:6] + b"\0\0" + frame[8:-2] + b"\0\0"


def _with_sequence(request: bytes, answer: bytes) -> bytes:
    """The recorded answer's frames with the request's sequence number and their CRC anew."""
    if not _is_ether(request):
        return answer
    frames, rest = _split_ether(answer)
    out = bytearray()
    for frame in frames:
        body = frame[:6] + request[6:8] + frame[8:-2]
        out += body + sbus.crc16(body).to_bytes(2, "big")
    return bytes(out + rest)


#: kind → what record and replay know of its protocol (see the module docstring's table).
PROTOCOLS: dict[str, Protocol] = {
    "sers": Protocol(split=_split_lines, decoder=_LineDecoder),
    "gms96": Protocol(
        split=_split_frames,
        decoder=_FrameDecoder,
        tolerances=(Tolerance("checksum", _without_checksum), Tolerance("fcb", _without_fcb)),
    ),
    "pcd4h3.ether_tcp": Protocol(
        split=_split_ether,
        decoder=_EtherDecoder,
        tolerances=(Tolerance("sequence", _without_sequence, _with_sequence),),
    ),
}

_PLAIN = Protocol()


def protocol_of(kind: str, port: str = "main") -> Protocol:
    """What is known of the protocol on ``port`` of ``kind``; byte-exact for one not in :data:`PROTOCOLS`."""
    return PROTOCOLS.get(f"{kind}.{port}") or PROTOCOLS.get(kind, _PLAIN)
