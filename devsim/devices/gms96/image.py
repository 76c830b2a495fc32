"""Process image, PLC markers, data area and message buffer of a GMS96 (manual §2.4.1, §2.4.2).

Spec §4.4 (special markers MB0..MB29), §4.5.1 (MB4 message code with a FIFO of buffered codes), §4.5.2 (MB5),
§4.11 (inputs EB0..EB3, outputs AB0..AB2), §3.8.3/§3.8.4 (data area: registers R0..R19 at byte
4·n, DW0..DW79 static).  Bits are addressed ``Ebyte.bit`` / ``Abyte.bit`` / ``Mbyte.bit``.
"""

from __future__ import annotations

import re
from collections import deque

__all__ = ["STATIC_BYTES", "ProcessImage", "bit_name", "parse_bit"]

#: A bit address with space or TAB around its parts (\s also took VT, FF and LF, and ``$`` a line end).
_BIT = re.compile(r"[ \t]*([EAM])[ \t]*(\d+)\.([0-7])[ \t]*", re.IGNORECASE | re.ASCII)
STATIC_BYTES = 160  # DW0..DW79 survive power-off (manual §2.3.1 d)
MESSAGE_FIFO = 8


def parse_bit(name: str) -> tuple[str, int, int]:
    """``"E2.1"`` → ``("E", 2, 1)``; ``ValueError`` for anything else."""
    m = _BIT.fullmatch(str(name))
    if not m:
        raise ValueError(f"not a bit address: {name!r} (e.g. E2.1, A0.2, M7.0)")
    return m.group(1).upper(), int(m.group(2)), int(m.group(3))


def bit_name(area: str, byte: int, bit: int) -> str:
    return f"{area}{byte}.{bit}"


class ProcessImage:
    """Markers MB0..MB255, data bytes 0..255, outputs AB0..AB2 and the MB4 message FIFO (manual
    §2.4.1, §2.4.2).

    Inputs live in the device's signal bank (``E0.0`` …) so the control API can flip them; the
    status bits of MB0/MB1/MB3 are overlaid by the card when it reads them
    (:data:`~devsim.devices.gms96.model.STATUS_MARKERS`).
    """

    def __init__(self) -> None:
        self.markers = bytearray(256)
        self.data = bytearray(256)
        self.outputs = bytearray(3)  # AB0, AB1, AB2 (analog out, 0..255)
        self.pending_messages: deque[int] = deque()
        self.pending_errors: deque[int] = deque()  # SNDF codes behind the one in MB5

    def clear(self) -> None:
        """Power-on: everything 0, no buffered message (the static data is restored after)."""
        self.markers[:] = bytes(len(self.markers))
        self.data[:] = bytes(len(self.data))
        self.outputs[:] = bytes(len(self.outputs))
        self.pending_messages.clear()
        self.pending_errors.clear()

    # -- markers ------------------------------------------------------------------------------
    def marker(self, byte: int, bit: int) -> bool:
        return bool(self.markers[byte] >> bit & 1)

    def set_marker(self, byte: int, bit: int, value: bool) -> None:
        if value:
            self.markers[byte] |= 1 << bit
        else:
            self.markers[byte] &= ~(1 << bit) & 0xFF

    # -- messages (MB4, §4.5.1) -----------------------------------------------------------------
    def post_message(self, code: int) -> None:
        """SNDM / firmware message: into MB4, or buffered behind the one waiting there."""
        self._buffered(4, self.pending_messages, code)

    def take_message(self) -> int | None:
        """Kurzsatz #1: the code in MB4 (cleared; the next buffered code moves up) or None."""
        code = self.markers[4]
        if not code:
            return None
        self.markers[4] = self.pending_messages.popleft() if self.pending_messages else 0
        return code

    # -- error byte (MB5, §4.5.2) ---------------------------------------------------------------
    def post_error(self, code: int) -> None:
        """SNDF: "Operand gebuffert in MB5 (Fehler-Byte) eintragen" (manual §2.4.3): into MB5, or
        buffered behind the code waiting there (0 enters nothing)."""
        self._buffered(5, self.pending_errors, code)

    def _buffered(self, byte: int, pending: deque[int], code: int) -> None:
        """``code`` into MB(byte), or behind the codes waiting for it (at most :data:`MESSAGE_FIFO`)."""
        code &= 0xFF
        if not code:
            return
        if self.markers[byte] == 0:
            self.markers[byte] = code
        elif len(pending) < MESSAGE_FIFO:
            pending.append(code)

    def write_marker_byte(self, byte: int, value: int) -> None:
        """MB(byte) written (PLC, ``p11``); once MB5 is cleared, the next buffered SNDF code moves up."""
        self.markers[byte] = value & 0xFF
        if byte == 5 and not self.markers[5] and self.pending_errors:
            self.markers[5] = self.pending_errors.popleft()

    # -- data area ------------------------------------------------------------------------------
    def write_register(self, n: int, value: int) -> None:
        """``c``: R(n) at bytes 4n..4n+3, value little-endian with sign byte (spec §3.8.3)."""
        self.data[4 * n : 4 * n + 4] = (value & 0xFFFFFFFF).to_bytes(4, "little", signed=False)
        if value < 0:
            self.data[4 * n + 3] = 0xFF

    def write_word(self, offset: int, value: int) -> None:
        """``d``: low byte at ``offset``, high byte at ``offset + 1`` (spec §3.8.4)."""
        self.data[offset] = value & 0xFF
        if offset + 1 < len(self.data):
            self.data[offset + 1] = (value >> 8) & 0xFF

    def read_bytes(self, area: bytes | bytearray, start: int, count: int) -> bytes:
        """``count`` bytes from ``start``; bytes beyond the area read 0."""
        return bytes(area[i] if 0 <= i < len(area) else 0 for i in range(start, start + count))

    def static_data(self) -> list[int]:
        return list(self.data[:STATIC_BYTES])

    def restore_static(self, values: list[int] | None) -> None:
        if values:
            for i, v in enumerate(values[:STATIC_BYTES]):
                self.data[i] = int(v) & 0xFF
