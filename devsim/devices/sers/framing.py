"""The SERS line protocol's framing on its port (manual §4.1): what record and replay, the telegram
tap and the monitor know of it.

A host's message ends after CR or LF (a CR/LF pair gives a second, one-byte message); the drive's
answers are text lines ending after a CR.  No tolerances: the answer echoes the line as typed.
"""

from __future__ import annotations

from typing import Any

from devsim.core.framing import MAX_PARTIAL, Framing, split_at

__all__ = ["LINES"]


def _split_lines(buffer: bytes) -> tuple[list[bytes], bytes]:
    """Messages end after CR or LF (a CR/LF pair gives a second, one-byte message)."""
    return split_at(buffer, (0x0D, 0x0A))


class LineDecoder:
    """Text lines (latin-1), each ending after a CR: ``"#P11?\\r"``, ``"\\nok1\\n\\r"``."""

    def __init__(self, direction: str) -> None:
        self.direction = direction
        self._rest = b""
        self._ends = (0x0D, 0x0A) if direction == "host" else (0x0D,)

    def feed(self, data: bytes) -> list[Any] | None:
        """The lines ``data`` completes.  Bytes without a line end are kept up to
        :data:`MAX_PARTIAL`; the byte after that shows them, and itself, as a piece of their own
        (garbage is not kept forever), wherever the chunks are cut: the pieces are the ones byte
        by byte would give."""
        lines, rest = split_at(self._rest + data, self._ends)
        out = []
        for line in lines:
            while len(line) > MAX_PARTIAL + 1:  # (more than the limit before its end)
                out.append(line[: MAX_PARTIAL + 1])
                line = line[MAX_PARTIAL + 1 :]
            out.append(line)
        while len(rest) > MAX_PARTIAL:
            out.append(rest[: MAX_PARTIAL + 1])
            rest = rest[MAX_PARTIAL + 1 :]
        self._rest = rest
        return [line.decode("latin-1") for line in out]


#: The SERS port's framing: ASCII lines.
LINES = Framing(split=_split_lines, decoder=LineDecoder)
