"""The IP247's traverse-program memory (manual §2.6.1, §4.3.17–§4.3.21, §6.3.10; spec ip247.md
§4.10): up to 255 programs numbered 0 … 255 in battery RAM, 6000 characters in all, 1023 per
program, stored contiguously in input order; the directory lists them in storage order.

Deleting a program compacts the memory (later programs move up) unless some program is
executing: then the program only leaves the directory and its characters stay counted (module
error 61).  Pure; the module keeps it in its non-volatile memory as plain data.
"""

from __future__ import annotations

import msgspec

from devsim.devices.ip247 import program as lang

__all__ = ["CAPACITY", "MAX_PROGRAMS", "ProgramStore", "Stored", "StoreError"]

CAPACITY = 6000  # characters
MAX_PROGRAMS = 255


class StoreError(ValueError):
    """A refused store operation with its module error number (spec §4.3)."""

    def __init__(self, error: int) -> None:
        super().__init__(f"module error {error}")
        self.error = error


class Stored(msgspec.Struct, frozen=True):
    """One program as stored: its text, the syntax error (0 = none) and the faulty block."""

    number: int
    text: str
    error: int = 0
    faulty: int = 0


class ProgramStore:
    """Programs in storage order, and the characters of gaps left by directory-only deletes."""

    def __init__(self, programs: list[Stored] | None = None, gaps: int = 0) -> None:
        self.programs: list[Stored] = list(programs or [])
        self.gaps = gaps

    @property
    def used(self) -> int:
        return sum(len(p.text) for p in self.programs) + self.gaps

    def get(self, number: int) -> Stored | None:
        return next((p for p in self.programs if p.number == number), None)

    def add(self, program: Stored, *, from_plc: bool) -> None:
        """BA22: a new program (spec §4.10): a used number is error 49 from the PLC, 20 from the
        PG (which may overwrite after asking, see :meth:`replace`); 255 programs: 18; no room: 24."""
        if self.get(program.number) is not None:
            raise StoreError(49 if from_plc else 20)
        if len(self.programs) >= MAX_PROGRAMS:
            raise StoreError(18)
        if self.used + len(program.text) > CAPACITY:
            raise StoreError(24)
        self.programs.append(program)

    def replace(self, program: Stored, *, executing: set[int]) -> None:
        """BA22 from the PG with overwrite allowed (spec §3.6.6): the old program of that number is
        deleted and the new one stored in one step; when the new one cannot be stored (no room:
        24), neither happens and the old one stays."""
        before = (list(self.programs), self.gaps)
        try:
            self.delete(program.number, executing=executing)
            self.add(program, from_plc=False)
        except StoreError:
            self.programs, self.gaps = before
            raise

    def delete(self, number: int, *, executing: set[int]) -> int:
        """BA23: 0, or 61 when the program only left the directory (another one executes)."""
        program = self.get(number)
        if program is None:
            raise StoreError(19)
        if number in executing:
            raise StoreError(51)
        self.programs.remove(program)
        if executing:
            self.gaps += len(program.text)  # not compacted while a program runs (§4.3.19)
            return 61
        self.gaps = 0  # a compacting delete closes every gap (the manual's recipe, §4.3.19)
        return 0

    def directory(self) -> list[tuple[int, int]]:
        """BA65: (number, record length in words) in storage order (spec §3.4.5)."""
        return [(p.number, 5 + (len(p.text) + 1) // 2) for p in self.programs]

    def to_json(self) -> dict[str, object]:
        return {"gaps": self.gaps, "programs": [[p.number, p.text, p.error, p.faulty] for p in self.programs]}

    @classmethod
    def from_json(cls, data: object) -> ProgramStore:
        """The store battery RAM holds; ValueError for what BA22 and teach-in never store (a
        hand-edited or damaged state file): a program number outside 0 … 255 or twice, a text no
        record carries (latin-1) or marked with another syntax error or faulty block than its
        check gives, more programs or characters than the memory holds."""
        # (only the two entries to_json writes: null, [], 0 or {} read as an empty memory before)
        if type(data) is not dict or sorted(data) != ["gaps", "programs"]:
            raise ValueError(f"the stored programs {data!r:.40} are no program memory")
        rows, gaps = data["programs"], data["gaps"]
        if type(rows) is not list or type(gaps) is not int or gaps < 0:
            raise ValueError("the stored programs are no program memory")
        programs = [_stored(row) for row in rows]
        store = cls(programs, gaps)
        numbers = [p.number for p in programs]
        if len(set(numbers)) != len(numbers) or len(programs) > MAX_PROGRAMS or store.used > CAPACITY:
            raise ValueError(f"the stored programs {numbers} are more than the memory holds, or one twice")
        return store


def _stored(row: object) -> Stored:
    """One stored program ``[number, text, error, faulty]`` as BA22 or teach-in stores it."""
    if type(row) is not list or [type(v) for v in row] != [int, str, int, int] or not 0 <= row[0] <= 255:  # (numbers 0 … 255)
        raise ValueError(f"the stored program {row!r:.40} is no program BA22 stores")
    program = Stored(*row)
    try:
        program.text.encode("latin-1")
        lang.parse(program.text)
        check = (0, 0)
    except UnicodeEncodeError:
        raise ValueError(f"the stored program {program.number} holds characters no record carries") from None
    except lang.SyntaxFault as fault:
        check = (fault.errno, fault.block)
    if (program.error, program.faulty) != check:
        raise ValueError(f"the stored program {program.number} is marked with syntax error {program.error} in block"
                         f" {program.faulty}, which its text does not give")
    return program
