"""Program storage of the SERS in simulated EEPROM (manual §4.3, §4.4, §4.5.3; spec §4.9).

The program is kept as its statement texts, grouped in the lines the user typed, in the
device's non-volatile memory (section ``program``); every change is written through at once,
as the real drive writes each character to its E²PROM.  Capacity follows the spec's cost model
G-MEM (2 KB standard, 8 KB with option P8).  This module stores, edits and lists; running
programs is the program interpreter's job.
"""

from __future__ import annotations

from collections.abc import Callable

from devsim.core.nvram import NonVolatileMemory
from devsim.devices.sers.errors import SersError

__all__ = ["ProgramMemory", "statement_cost"]

SECTION = "program"


def statement_cost(text: str) -> int:
    """Bytes a statement occupies (spec §4.9 G-MEM)."""
    stripped = text.strip()
    if stripped.startswith('"'):
        return 2 + max(0, len(stripped) - 2)
    if stripped.startswith("//"):
        return 0
    if any(ch.isdigit() for ch in stripped):
        return 6
    return 2


class ProgramMemory:
    """The one stored program: a list of lines, each a list of statement texts."""

    def __init__(self, nvram: NonVolatileMemory, capacity: int = 2048) -> None:
        self.nvram = nvram
        self.capacity = capacity
        self.editing = False
        self.position = 0  # statement index where PGM inserts
        stored = nvram.get(SECTION, {"lines": []})
        self._lines: list[list[str]] = [list(line) for line in stored.get("lines", [])]

    # -- persistence -----------------------------------------------------------------------
    def _store(self) -> None:
        self.nvram.put(SECTION, {"lines": self._lines})

    def reload(self) -> None:
        stored = self.nvram.get(SECTION, {"lines": []})
        self._lines = [list(line) for line in stored.get("lines", [])]
        self.editing = False

    # -- queries ---------------------------------------------------------------------------
    def lines(self) -> list[list[str]]:
        return [list(line) for line in self._lines]

    def statements(self) -> list[str]:
        return [stmt for line in self._lines for stmt in line]

    @property
    def valid(self) -> bool:
        return bool(self.statements())

    def used_bytes(self) -> int:
        return sum(statement_cost(s) for s in self.statements())

    def free_words(self) -> int:
        return max(0, self.capacity - self.used_bytes()) // 2

    # -- editing ---------------------------------------------------------------------------
    def new(self) -> None:
        self._lines = []
        self.position = 0
        self.editing = True
        self._store()

    def edit(self) -> None:
        self.editing = True

    def quit(self) -> None:
        self.editing = False

    def add(self, text: str, new_line: bool) -> None:
        """Store a statement typed in programming mode (at the end of the program)."""
        if self.used_bytes() + statement_cost(text) > self.capacity:
            raise SersError(5)
        if new_line or not self._lines:
            self._lines.append([text])
        else:
            self._lines[-1].append(text)
        self._store()

    def listing(self, options: int, render: Callable[[str], str] = str) -> list[str]:
        """LIST output (spec G-LIST, manual §4.3, P1028): one statement per row, numbered
        ``n: `` with bit 0; with bit 3 the user's lines are kept, numbered by their first
        statement; with bit 2 labels start in column 1 and statements in column 4.
        ``render`` turns a stored statement into its listed form (full decimals, units)."""
        rows: list[str] = []
        number = 1
        for line in self._lines:
            groups = [line] if options & 8 else [[stmt] for stmt in line]
            for group in groups:
                text = " ".join(render(stmt) for stmt in group)
                if options & 4 and not _is_label(group[0]):
                    text = "   " + text
                rows.append(f"{number}: {text}" if options & 1 else text)
                number += len(group)
        return rows


def _is_label(text: str) -> bool:
    stripped = text.strip().upper()
    return stripped.startswith("L") and stripped[1:2].isdigit()
