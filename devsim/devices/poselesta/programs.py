"""The program memory: programs P00 … P98, their protection (POS III), the unit they were typed
in, and the tool catalogue (manual §2.3.14, §2.3.21, §2.6, §2.6.3; spec poselesta.md §3.2.2,
§4.5 G-LOCK, §4.9, §5.1).  Everything is kept in the control's non-volatile memory.

The blocks a read-in stores from one chunk of the host's bytes (what one write carries: a whole
tape, often) are written to that memory together, once, when the chunk has been taken
(:meth:`ProgramMemory.flush`, called by the links): before the control handles anything else
(the next bytes, a control request, a power cycle), so that a block counted (``v7.blocks``) is
one a ``kill -9`` keeps.  Each block written on its own rewrote every stored program, so a tape
of n blocks cost O(n²) and stalled the simulator for seconds (spec §3.5.5: the ports work in
parallel).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

from devsim.core.nvram import NonVolatileMemory, numbered, stored_whole
from devsim.core.points import BadValue, ascii_digits, strip_blanks
from devsim.devices.poselesta.codes import WERTBEREICHES_UEBERLAUF
from devsim.devices.poselesta.tape import Block, Formats, block_words, parse_blocks

__all__ = ["CATALOGUE", "DIAGNOSTICS", "RESERVED_PROGRAMS", "ProgramMemory"]

DIAGNOSTICS, CATALOGUE = 79, 99
RESERVED_PROGRAMS = (DIAGNOSTICS, CATALOGUE)  # the diagnostics and the parameter catalogue (spec §4.9)
NC_PROGRAMS = frozenset(range(99)) - {DIAGNOSTICS}  # what a read-in or program entry stores


class ProgramMemory:
    """The stored programs and tools of one control (manual §2.6.3, §2.3.21; spec §4.5, §4.9).

    ``formats(inch)`` are the word formats of a program typed in mm or in inch; ``inch()`` is
    the input V22/2 (programs are entered in inch while it is H); ``lock_open()`` the program
    lock V22/9; ``record`` notes a refusal in the event log.  ``protection`` says whether the
    variant has the program lock (POS III)."""

    def __init__(self, nvram: NonVolatileMemory, *, formats: Callable[[bool], Formats], inch: Callable[[], bool],
                 lock_open: Callable[[], bool], record: Callable[[str], None], max_blocks: int,
                 protection: bool) -> None:
        self._nvram = nvram
        self._formats = formats
        self._inch = inch
        self._lock_open = lock_open
        self._record = record
        self._max_blocks = max_blocks
        self._protection = protection
        self.programs: dict[int, dict[int, Block]] = {}
        self.protected: set[int] = set()
        self.inch_programs: set[int] = set()
        self.tools: dict[int, dict[str, float]] = {}
        self.mdi = ""  # the block entered for Hand-Einzelsatz (§2.4.7)
        self._unsaved = False  # blocks stored since the last save (see flush)
        self.load()

    # -- memory -------------------------------------------------------------------------------
    def load(self) -> None:
        """The memory as the control stored it; what it never stores (a hand-edited or damaged
        state file: a program, protected or inch program outside P00 … P98, a tool outside
        T01 … T99 or other than its radius and length as finite numbers, a number key not written
        as the control writes it (``str(n)``: not ``'٣'``, ``'03'``, ``'+3'``), a block number
        twice in a program) is a ValueError, and the start refuses the memory naming the file."""
        nvram = self._nvram
        # each section as its save writes it, an object or a list (maybe empty); absent: nothing
        # stored yet.  (``or {}`` read null, 0 and "" as an empty memory, without a word.)
        self.programs = {number: _blocks(number, blocks)
                         for number, blocks in numbered(nvram.get("programs", {}), "program", NC_PROGRAMS).items()}
        # [SIM-CHOICE] more blocks than the configured memory holds (a file of a control configured
        # larger, or hand-edited): no manual says what a control does at power-on with programs it
        # cannot hold, and no read-in or entry stores them, so the start refuses the memory
        total = sum(len(blocks) for blocks in self.programs.values())
        if total > self._max_blocks:
            raise ValueError(f"the stored programs hold {total} blocks, more than the configured"
                             f" max_blocks_total {self._max_blocks}")
        self.protected = {stored_whole(p, "protected program", range(99)) for p in _listed(nvram, "protected")}
        if not self._protection:  # [SIM-CHOICE] a POS III's protection in the memory of a control now
            self.protected = set()  # configured as a POS II (no program lock): stays stored, not enforced
        self.inch_programs = {stored_whole(p, "inch program", NC_PROGRAMS) for p in _listed(nvram, "inch_programs")}
        self.tools = {t: _tool(t, v) for t, v in numbered(nvram.get("tools", {}), "tool", range(1, 100)).items()}

    def _save(self, typed: tuple[int, bool] | None = None) -> None:
        """The programs; with ``typed`` (a program entered or read in anew, and whether in inch) its
        inch mark in the same write: written one after the other, a kill between them left a
        program typed in inch marked as mm (its numbers read with other decimals)."""
        self._unsaved = False
        sections: dict[str, Any] = {
            "programs": {str(p): [b.to_json() for _, b in sorted(bs.items())] for p, bs in self.programs.items()}}
        if typed is not None and self._retyped(*typed):
            sections["inch_programs"] = sorted(self.inch_programs)
        self._nvram.put_sections(sections)

    def flush(self) -> None:
        """Write the blocks stored since the last save (the links, at the end of each chunk of a
        read-in; the control, as it closes)."""
        if self._unsaved:
            self._save()

    # -- programs -----------------------------------------------------------------------------------
    def blocks(self, number: int) -> list[Block]:
        """The blocks of a program in ascending N."""
        return sorted(self.programs.get(number, {}).values(), key=lambda b: b.number)

    def to_run(self, number: int, hand_block: bool) -> tuple[list[Block], bool]:
        """The blocks to execute and whether they were typed in inch: program ``number``, or in
        Hand-Einzelsatz the block entered (typed in inch while V22/2 is H)."""
        if not hand_block:
            return self.blocks(number), number in self.inch_programs
        inch = self._inch()
        try:
            return (parse_blocks(self.mdi, self._formats(inch)) if self.mdi.strip() else []), inch
        except ValueError:
            return [], inch

    def program_formats(self, number: int) -> Formats:
        """The word formats a program was typed in: mm, or inch with two more decimals."""
        return self._formats(number in self.inch_programs)

    def _retyped(self, number: int, inch: bool) -> bool:
        """Mark program ``number`` as typed in inch or mm; whether its mark changed."""
        if inch == (number in self.inch_programs):
            return False
        (self.inch_programs.add if inch else self.inch_programs.discard)(number)
        return True

    def refuse_protected(self, number: int) -> None:
        if number in self.protected:
            self._record("program_protected")
            raise BadValue(f"P{number:02d} is protected: release it first (program lock open)")

    def clear_for_read_in(self, number: int) -> None:
        """A read-in starts: "zuerst das vorgewählte Programm gelöscht" (§2.6)."""
        self.programs.pop(number, None)
        self._save(typed=(number, self._inch()))

    def store_block(self, program: int, block: Block) -> str | None:
        """A block read in; returns why it cannot be stored (the read-in fails), or None.  A
        program the memory has no room for is not listed at all (spec §3.5.3: the blocks
        committed before a failure remain; §2.6: the pre-selected program was deleted)."""
        blocks = self.programs.get(program, {})
        total = sum(len(b) for b in self.programs.values())
        if block.number not in blocks and total >= self._max_blocks:
            return "memory full"
        self.programs[program] = blocks
        blocks[block.number] = block
        self._unsaved = True  # (saved with the chunk's other blocks: flush)
        return None

    def program_text(self, number: int) -> str:
        formats = self.program_formats(number)
        return "\n".join(" ".join(block_words(b, formats, formatted=True)) for b in self.blocks(number))

    def set_program_text(self, number: int, text: str) -> None:
        """Program entry (spec §3.2.2 ``panel.edit_block``): blocks typed as text replace the
        program; the same rules as a read-in."""
        if number in RESERVED_PROGRAMS:
            raise BadValue(f"P{number:02d} is not an NC program")
        self.refuse_protected(number)
        inch = self._inch()
        try:
            blocks = parse_blocks(text, self._formats(inch))
        except ValueError as exc:
            raise BadValue(str(exc)) from None
        others = sum(len(b) for p, b in self.programs.items() if p != number)
        if others + len(blocks) > self._max_blocks:
            raise BadValue(f"{WERTBEREICHES_UEBERLAUF}: program memory full")
        if blocks:
            self.programs[number] = {b.number: b for b in blocks}
        else:
            self.programs.pop(number, None)
        self._save(typed=(number, inch))

    def edit_block(self, text: str) -> None:
        """Program entry of one block (spec §3.2.2 ``panel.edit_block``): ``"20: N5 X10"`` stores
        (or replaces) block N5 of P20, by the rules of a read-in, and saves it at once with a new
        program's inch mark (before, the mark was written first, and the block only at the next
        read-in chunk or at the end: a kill lost the block and left the mark of a program not
        stored)."""
        number_text, sep, block_text = text.partition(":")
        digits = strip_blanks(number_text).lstrip("Pp")  # (str.strip: NBSP, U+3000, FS … US too)
        if not sep or not ascii_digits(digits):
            raise BadValue("expected 'program: block', e.g. '20: N5 X10'")
        number = int(digits)
        if number in RESERVED_PROGRAMS or not 0 <= number <= 98:
            raise BadValue(f"P{number:02d} is not an NC program")
        self.refuse_protected(number)
        # a new program is typed in inch while V22/2 is H; a stored one keeps the unit it was typed in
        inch = self._inch() if number not in self.programs else number in self.inch_programs
        try:
            blocks = parse_blocks(block_text, self._formats(inch))
        except ValueError as exc:
            raise BadValue(str(exc)) from None
        if len(blocks) != 1:
            raise BadValue("exactly one block with its number N is entered at a time")
        problem = self.store_block(number, blocks[0])
        if problem is not None:
            raise BadValue(f"{WERTBEREICHES_UEBERLAUF}: {problem}")
        self._save(typed=(number, inch))  # the block with a new program's inch mark, in one write

    # -- program lock (POS III, §2.3.21; spec §4.5 G-LOCK) ------------------------------------------
    def protect(self, number: int, on: bool) -> None:
        """Protect a program (in any position of V22/9) or release it (only while V22/9 is H)."""
        if not self._protection:
            raise BadValue("program protection is a POS III function")
        if not on and not self._lock_open():
            self._record("program_locked")
            raise BadValue(f"P{number:02d} can only be released with the program lock open (V22/9 H)")
        (self.protected.add if on else self.protected.discard)(number)
        self._nvram.put("protected", sorted(self.protected))

    # -- the tool catalogue (spec §4.9) --------------------------------------------------------------
    def set_tool(self, number: int, value: Any) -> None:
        """Radius and length of T01 … T99, in the catalogue's unit (P1); kept in memory, not
        transferable serially."""
        if not isinstance(value, dict) or set(value) - {"radius", "length"}:
            raise BadValue('expected {"radius": r, "length": l}')
        entry = {}
        for key in ("radius", "length"):
            number_value = value.get(key, 0.0)
            if isinstance(number_value, bool) or not isinstance(number_value, int | float) or \
                    not math.isfinite(number_value):
                raise BadValue(f"T{number:02d}.{key}: a finite number")
            entry[key] = float(number_value)
        self.tools[number] = entry
        self._nvram.put("tools", {str(t): v for t, v in sorted(self.tools.items())})


def _listed(nvram: NonVolatileMemory, section: str) -> list[Any]:
    """A section the control stores as a list of numbers (``sorted(set)``, maybe empty)."""
    stored = nvram.get(section, [])
    if type(stored) is not list:
        raise ValueError(f"the stored {section} {stored!r:.40} are no list of programs the control writes")
    return stored


def _blocks(program: int, stored: object) -> dict[int, Block]:
    """A stored program's blocks by their numbers, as :meth:`ProgramMemory.store_block` keeps them:
    a number once (a second block N5 replaces the first as it is read in or entered)."""
    if type(stored) is not list:
        raise ValueError(f"stored program P{program:02d} {stored!r:.40} is no list of blocks")
    blocks = [Block.from_json(b) for b in stored]
    numbers = {b.number: b for b in blocks}
    if len(numbers) != len(blocks):
        raise ValueError(f"stored program P{program:02d} holds a block number twice")
    return numbers


def _tool(key: object, value: object) -> dict[str, float]:
    """A stored tool as :meth:`ProgramMemory.set_tool` stores it: its radius and length."""
    if type(value) is not dict or set(value) != {"radius", "length"} or not all(
            type(v) in (int, float) and math.isfinite(v) for v in value.values()):
        raise ValueError(f"stored tool T{key} {value!r:.60} is no radius and length")
    return {k: float(v) for k, v in value.items()}
