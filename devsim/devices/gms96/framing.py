"""The GMS96 link's framing on its port (spec §3.2, DIN 19244 FT1.2): what record and replay, the
telegram tap and the monitor know of it.

Host messages are FT1.2 frames cut by structure with the card's own
:class:`~devsim.devices.gms96.codec.FrameDecoder`.  Tolerances for replay: ``checksum`` (the CS
octet ignored) and ``fcb`` (the frame count bit, 20h of C, and with it the checksum ignored: a
host toggles FCB per frame, spec §3.3).
"""

from __future__ import annotations

from typing import Any

from devsim.core.framing import Framing, Tolerance
from devsim.devices.gms96 import codec as ft12

__all__ = ["FT12"]


def _card_decoder() -> ft12.FrameDecoder:
    return ft12.FrameDecoder(short_extension=ft12.short_extension_device)


def _split_frames(buffer: bytes) -> tuple[list[bytes], bytes]:
    decoder = _card_decoder()
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


class FrameDescriber:
    """FT1.2 frames of one direction, described field by field."""

    def __init__(self, direction: str) -> None:
        self.direction = direction
        self._from_host = direction == "host"
        if direction == "host":  # what the card receives
            self._decoder = _card_decoder()
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


def _label(described: dict[str, Any]) -> str:
    """A described frame in a few characters: a letter with its parameters (``M 20000``), a
    Kurzsatz command (``#1``), the acknowledgement ``E5``, else the frame's C field and data."""
    if "error" in described:
        return f"bad frame: {described['error']}"
    if "letter" in described:
        return " ".join([str(described["letter"]), *map(str, described.get("params", []))])
    if "command" in described:
        return str(described["command"])
    if described.get("frame") == "single":
        return str(described["value"])
    return " ".join([f"C={described.get('C', '?')}", *([str(described["data"])] if "data" in described else [])])


#: The GMS96 port's framing: FT1.2 frames, with the checksum and FCB tolerances.
FT12 = Framing(
    split=_split_frames,
    decoder=FrameDescriber,
    tolerances=(Tolerance("checksum", _without_checksum), Tolerance("fcb", _without_fcb)),
    label=_label,
)
