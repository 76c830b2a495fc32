"""Ether-S-Bus framing on the PCD4.H3's TCP port (manual §9.3; spec pcd4h3 §9.3): what record and
replay, the telegram tap and the monitor know of it.

Frames are cut by their length field (:class:`~devsim.devices.pcd4h3.sbus.EtherReceiver`).  The
replay tolerance ``sequence``: another sequence number (and so CRC) is the same request; the
recorded answer gets the host's sequence number and a new CRC.
"""

from __future__ import annotations

from typing import Any

from devsim.core.framing import Framing, Tolerance
from devsim.devices.pcd4h3 import sbus

__all__ = ["ETHER_TCP"]

_ETHER_HEADER = 9  # length (4), version, type, sequence (2), attribute


def _split_ether(buffer: bytes) -> tuple[list[bytes], bytes]:
    receiver = sbus.EtherReceiver()
    frames = receiver.feed(buffer)
    rest = buffer[sum(len(frame) for frame in frames) :]
    if len(rest) >= 4 and not sbus.ether_length_ok(int.from_bytes(rest[:4], "big")):
        return [*frames, rest], b""  # not a frame: one message, so that it is reported
    return frames, rest


class EtherDescriber:
    """Ether-S-Bus frames of one direction: sequence, attribute, payload, station, command, CRC."""

    _ATTRIBUTES = {sbus.REQUEST: "request", sbus.RESPONSE: "response", sbus.ACK_NAK: "ack/nak"}

    def __init__(self, direction: str) -> None:
        self.direction = direction
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


#: The Ether-S-Bus TCP port's framing: frames by length, with the sequence tolerance.
ETHER_TCP = Framing(
    split=_split_ether,
    decoder=EtherDescriber,
    tolerances=(Tolerance("sequence", _without_sequence, _with_sequence),),
)
