"""The axis attribute byte RMLD ("Rückmeldungen", FB164 DL n+12; manual §2.7, §6.2.4; spec
ip247.md §4.1.2) and the framing of the simulator's PLC-side TCP endpoint (spec §3.7).  Pure."""

from __future__ import annotations

import struct

__all__ = ["AgFramer", "UNIT_BITS", "ag_frame", "rmld"]

#: Unit code in bits 1…0 as the manual's figure shows it (metric 02H, inch 00H, degree 01H),
#: by the machine data's unit (1 mm, 2 inch, 3 degree) — spec §4.1.2 [DECISION].
UNIT_BITS = {1: 0x02, 2: 0x00, 3: 0x01}


def rmld(*, unit: int, in_position: bool, reference_sync: bool, teach_in: bool, reference_missing: bool,
         md_missing: bool, finished: bool) -> int:
    """Bits: 1…0 unit, 2 in position, 3 reference point synchronous (MD n+25 = 0), 4 teach-in,
    5 reference point missing, 6 machine data missing, 7 job finished ("fertig")."""
    return (UNIT_BITS.get(unit, 0) | in_position << 2 | reference_sync << 3 | teach_in << 4
            | reference_missing << 5 | md_missing << 6 | finished << 7)


def ag_frame(function: int, payload: bytes) -> bytes:
    """One message of the PLC-side endpoint: big-endian length of the rest, function, payload."""
    return struct.pack(">HB", 1 + len(payload), function) + payload


class AgFramer:
    """Messages out of a TCP byte stream (any cut): ``feed`` gives the complete ``(function,
    payload)`` pairs; a zero length is skipped.  A message waits for all the bytes its length
    promises, whatever follows them and however long: at most 65,535 are held.  [SIM-CHOICE] no
    timeout: §3.7 says nothing of a gap (the real AG side is a dual-port RAM, nothing to frame),
    TCP delivers a message whole, and a PLC client out of step reconnects (the face makes a new
    framer when its host leaves)."""

    def __init__(self) -> None:
        self._buffer = bytearray()

    def feed(self, data: bytes) -> list[tuple[int, bytes]]:
        self._buffer += data
        messages = []
        while len(self._buffer) >= 2:
            (length,) = struct.unpack_from(">H", self._buffer)
            if len(self._buffer) < 2 + length:
                break
            body = bytes(self._buffer[2 : 2 + length])
            del self._buffer[: 2 + length]
            if body:
                messages.append((body[0], body[1:]))
        return messages
