"""An IP247 axis's coordinate system: zero offsets and tool offsets (manual §2.6.6.6,
§2.6.6.7, §4.3.5–§4.3.9; spec ip247.md §4.11.6, §4.11.7, §5.9; vectors §5.9, §6.6, §6.7).

The reported actual value is the tool tip's coordinate: holder position (physical, base units,
as the reference run set it) plus the tool offsets, minus the zero offsets —
A = H + (to_ba15 + to_prog) − (zo_mode + zo_prog).  A positive zero offset moves the origin in
the positive direction.  On a rotary axis the actual value is wrapped into the traverse range,
which the zero offsets shift with it.  Pure: operations return a module error number or None.
"""

from __future__ import annotations

import msgspec

from devsim.devices.ip247.machine_data import LIMIT

__all__ = ["Coordinates"]


class Coordinates(msgspec.Struct):
    """The offsets of one axis, and the machine data's limits they must respect."""

    limit_begin: int  # SW limit / range start, in the reference system
    limit_end: int
    reference: int
    rotary: bool = False
    zo_mode: int = 0  # BA12 / BA13 (and leftovers of aborted programs)
    zo_prog: int = 0  # G54 … G57 of the running program
    to_ba15: int = 0
    to_prog: int = 0  # G43 / G44

    @property
    def zero_offset(self) -> int:
        return self.zo_mode + self.zo_prog

    @property
    def tool_offset(self) -> int:
        return self.to_ba15 + self.to_prog

    def range(self) -> tuple[int, int]:
        """The SW limits / the rotary range in actual-value coordinates."""
        return self.limit_begin - self.zero_offset, self.limit_end - self.zero_offset

    def actual(self, holder: int) -> int:
        value = holder + self.tool_offset - self.zero_offset
        if self.rotary:
            begin, end = self.range()
            value = begin + (value - begin) % (end - begin)
        return value

    def holder_for(self, target: int) -> int:
        """Where the holder goes for the tool tip to reach ``target`` (actual coordinates)."""
        return target - self.tool_offset + self.zero_offset

    # -- BA12 … BA16 (spec §5.9) ----------------------------------------------------------------------
    def _shift(self, change: int) -> int | None:
        shifted = self.zo_mode + change + self.zo_prog
        values = (self.limit_begin - shifted, self.limit_end - shifted, self.reference - shifted)
        if any(abs(v) > LIMIT for v in values):
            return 23  # the shift would put a coordinate beyond ±100 m
        self.zo_mode += change
        return None

    def set_actual(self, holder: int, value: int) -> int | None:
        """BA12: the current position gets the coordinate ``value``."""
        if abs(value) > LIMIT:
            return 62
        return self._shift(self.actual(holder) - value)

    def shift(self, distance: int, forward: bool) -> int | None:
        """BA13: the origin moves by ``distance`` forward (Vorwärts) or backward."""
        if abs(distance) > LIMIT:
            return 62
        return self._shift(distance if forward else -distance)

    def clear_shifts(self) -> None:
        """BA14: every BA12/BA13 shift (and leftovers of aborted programs)."""
        self.zo_mode = 0

    def set_tool(self, value: int, forward: bool) -> int | None:
        """BA15: the tool offset is ±value (the program part is dropped)."""
        if abs(value) > LIMIT:
            return 62
        offset = value if forward else -value
        error = self._tool_error(offset)
        if error is not None:
            return error
        self.to_ba15, self.to_prog = offset, 0
        return None

    def clear_tools(self) -> None:
        """BA16: the BA15 and program tool offsets."""
        self.to_ba15 = self.to_prog = 0

    def _tool_error(self, total: int) -> int | None:
        if self.rotary:
            return 63 if abs(total) >= self.limit_end - self.limit_begin else None
        if abs(total) > LIMIT or self.limit_end + total > LIMIT or self.limit_begin + total < -LIMIT:
            return 23
        return None

    # -- in programs (spec §4.11.6, §4.11.7) ------------------------------------------------------------
    def program_shift(self, zero_offset: int) -> None:
        """G54 … G57: this one replaces any other program shift; G53 passes 0."""
        self.zo_prog = zero_offset

    def program_tool(self, md_tool: int, positive: bool) -> int | None:
        """G43 / G44: add / subtract the machine data's tool length again (error 63)."""
        total = self.to_ba15 + self.to_prog + (md_tool if positive else -md_tool)
        if self._tool_error(total) is not None:
            return 63
        self.to_prog += md_tool if positive else -md_tool
        return None

    def program_end(self) -> None:
        """The normal end of a main program clears its shifts (tool offsets stay)."""
        self.zo_prog = 0
