"""The IP247's traverse programs as the axes use them: the program memory, starting a program on
an axis (BA8, BA9) and teach-in (BA10, BA11, Übernahme) (manual §2.6, §4.3.1–§4.3.4; spec
ip247.md §4.10, §5.11, §5.12).

The memory itself is :class:`.store.ProgramStore`; a running program is a
:class:`.automatic.ProgramRun` in its axis's ``automatic``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from devsim.devices.ip247 import program as lang
from devsim.devices.ip247.automatic import ProgramRun
from devsim.devices.ip247.axis_unit import AxisUnit
from devsim.devices.ip247.jobs import START, STOP, TAKE_OVER
from devsim.devices.ip247.store import CAPACITY, ProgramStore, Stored

__all__ = ["ProgramJobs"]


class ProgramJobs:
    """The programs part: the program memory in battery RAM and the jobs that run or teach
    programs on the axes (spec §5.11, §5.12).  ``save`` writes battery RAM."""

    def __init__(self, units: Sequence[AxisUnit], save: Callable[[], None]) -> None:
        self.units, self.save = units, save
        self.store = ProgramStore()

    def executing(self) -> set[int]:
        """The numbers of the programs the axes execute: each one started and the subprograms
        it is in (manual §4.3.1)."""
        return {n for u in self.units if u.automatic is not None for n in (u.automatic.number, *u.automatic.calls)}

    def teach_in_active(self) -> bool:
        return any(u.teach_in is not None for u in self.units)

    def program_job(self, unit: AxisUnit, cmd: int, number: int) -> int | None:
        """BA8/BA9 while the axis is "fertig" (spec §4.2, §5.11)."""
        run = unit.automatic
        assert run is None or isinstance(run, ProgramRun)
        if cmd == STOP:
            if run is None:
                return None
            error, _ = run.stop_at_rest()
            return error
        if cmd == TAKE_OVER:
            return run.take_over() if run is not None else 2
        if cmd != START:
            return 2
        if run is not None:
            run.abort()
        stored = self.store.get(number)
        if stored is None:
            return 19
        if stored.error:
            return 48
        programs = {}
        for p in self.store.programs:
            if not p.error:
                programs[p.number] = lang.parse(p.text)
        started = ProgramRun(unit, number, unit.mode == 9, programs)
        unit.automatic = started
        started.start()
        return None

    def teach_job(self, unit: AxisUnit, cmd: int, number: int) -> int | None:
        """BA10 (teach-in on for a new program) and BA11 (close it with M02), spec §5.12."""
        if unit.mode == 10:
            if self.teach_in_active():
                return 22  # one axis at a time
            if self.store.get(number) is not None:
                return 49
            if self.store.used + len(self._teach_text(number, [])) > CAPACITY:
                return 24
            unit.teach_in, unit.taught = number, []
            return None
        if unit.teach_in is None:
            return 2
        self._close_teach_in(unit)
        return None

    @staticmethod
    def _teach_text(number: int, blocks: list[str]) -> str:
        """The generated program (spec §5.12 [DECISION]): ``%  7``, ``N1 X1258.250 F2500``, ``N3 M02``."""
        return "".join(f"{line}\n" for line in (f"%{number:3d}", *blocks, f"N{len(blocks) + 1} M02"))

    def _close_teach_in(self, unit: AxisUnit) -> None:
        number, unit.teach_in = unit.teach_in, None
        assert number is not None
        self.store.add(Stored(number, self._teach_text(number, unit.taught)), from_plc=False)
        self.save()

    def teach_store(self, unit: AxisUnit) -> int | None:
        """Übernahme in teach-in at standstill: the actual value becomes a block with the MD
        step velocity, message 3 "Satz abgespeichert" (spec §5.12).  A block that would take the
        memory past its 6000 characters (§4.3.4) or the program past the 1023 one program may
        have (§2.6.1: "Pro Programm sind maximal 1023 ASCII-Zeichen zulässig") ends teach-in."""
        if unit.teach_in is None or unit.md is None:
            return 2
        block = f"N{len(unit.taught) + 1} X{unit.actual() / 1000:.3f} F{unit.md.step_velocity}"
        text = self._teach_text(unit.teach_in, [*unit.taught, block])
        if self.store.used + len(text) > CAPACITY or len(text) > lang.MAX_TEXT:
            unit.taught[-1:] = []  # memory full: the last stored block makes way for the end block
            self._close_teach_in(unit)
            return 24
        unit.taught.append(block)
        return 3
