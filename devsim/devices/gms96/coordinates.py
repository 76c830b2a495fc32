"""Coordinate frames of the GMS96: physical, machine and work positions, zero and tool offsets
(manual §2.3.1 G, O, T0; spec §3.8.6, §3.8.11, §5.1, §5.9).

The axis runs in *physical* increments; the position counter (machine frame) is
``physical - origin``; the work frame subtracts the active zero offset (G54..G69) and the tool
offset.  The zero-offset table and the machine zero are non-volatile.
"""

from __future__ import annotations

from devsim.core.axis import Axis
from devsim.core.nvram import NonVolatileMemory, numbered, stored_object, stored_whole
from devsim.devices.gms96 import tables
from devsim.devices.gms96.codec import S24_MAX, S24_MIN

__all__ = ["P2_VALUES", "ZERO_POINTS", "Coordinates"]

#: the zero points G54 … G57 and the extended G54 … G69 (spec §3.8.6)
ZERO_POINTS = range(54, 70)
#: what a telegram's parameter carries (24 bits, signed, spec Appendix B): a stored offset
P2_VALUES = range(S24_MIN, S24_MAX + 1)


class Coordinates:
    """The frames and modal coordinate settings of one card (manual §2.3.1 G, O; spec §5.9)."""

    def __init__(self, axis: Axis, nvram: NonVolatileMemory, tool_offset: int) -> None:
        self.axis = axis
        self.nvram = nvram
        #: The tool offset T: configured, set through the control API (no command sets it, spec §5.9).
        self.tool_offset = tool_offset
        self.origin = 0.0  # physical position of machine 0
        self.zero_table: dict[int, int] = {}  # G54..G69 → offset
        self.machine_zero = 0  # G53;P2;1: stored, not used internally
        self.active_zero: int | None = None
        self.tool_active = True
        self.before_g53: tuple[int | None, bool] = (None, True)
        self.g_relative = False  # G91
        self.g92 = 0  # G96's speed limit [rpm], 0 = none
        self.g96: int | None = None  # G96 cutting speed

    def power_on(self, reset_origin: bool) -> None:
        """The offsets from memory, G53 G90, no G92/G96; ``reset_origin``: machine 0 := here."""
        if reset_origin:
            self.origin = self.axis.position()
        # what save() writes: the table (maybe empty) and the machine zero (null, {} or a table of
        # null read as none stored before)
        offs = {"table": {}, "machine_zero": 0}  # (no zero point entered yet, or a wiped memory)
        if "offsets" in self.nvram:
            offs = stored_object(self.nvram.get("offsets"), "offsets", offs)
        # what G54..G69 / G53 with P3 = 1 store: a zero point 54 … 69 (its key as str(n)) and a
        # P2 of the 24-bit telegram; anything else refuses the memory at the start (UnfitMemory):
        # int() took '٥٥', '+55', 1.5, true and "3" as they were, and the key '-55' or 10**30
        self.zero_table = {zp: stored_whole(v, "zero offset", P2_VALUES)
                           for zp, v in numbered(offs["table"], "zero point", ZERO_POINTS).items()}
        self.machine_zero = stored_whole(offs["machine_zero"], "machine zero", P2_VALUES)
        self.g_relative = False
        self.active_zero = None
        self.tool_active = True
        self.before_g53 = (None, True)
        self.g92 = 0
        self.g96 = None

    def save(self) -> None:
        self.nvram.put("offsets", {"table": {str(k): v for k, v in self.zero_table.items()}, "machine_zero": self.machine_zero})

    # -- frames ---------------------------------------------------------------------------------
    def physical_to_machine(self, x: float) -> float:
        return x - self.origin

    def machine_to_physical(self, m: float) -> float:
        return m + self.origin

    def offsets(self) -> float:
        """The active zero offset plus the tool offset (when active)."""
        z = self.zero_table.get(self.active_zero, 0) if self.active_zero is not None else 0
        return z + (self.tool_offset if self.tool_active else 0)

    def work_to_physical(self, w: float) -> float:
        return w + self.offsets() + self.origin

    def setpoint_work(self) -> int:
        """The set-point in the work frame (``T0``)."""
        return int(round(self.axis.position() - self.origin - self.offsets()))

    def set_counter_here(self, value: float) -> None:
        """Position counter := ``value`` (machine coordinates) at the current set-point."""
        self.origin = self.axis.position() - value

    def set_work_position(self, value: int) -> None:
        """``O``: the position in the work frame := ``value``, no motion (spec §3.8.11)."""
        value = max(tables.POSITION_MIN, min(tables.POSITION_MAX, value))
        self.origin = self.axis.position() - value - self.offsets()

    # -- G functions (spec §3.8.6) --------------------------------------------------------------------
    def deselect(self, without_tool: bool) -> None:
        """G53 (;1: the tool offset too); G5x;1 re-selects what was active."""
        self.before_g53 = (self.active_zero, self.tool_active)
        self.active_zero = None
        if without_tool:
            self.tool_active = False

    def reselect(self) -> None:
        self.active_zero, self.tool_active = self.before_g53

    def g96_rpm(self) -> float | None:
        """The G96 desired spindle speed now, ``n = C / r`` limited by G92 (None: G96 not selected)."""
        if self.g96 is None:
            return None
        r = max(1, abs(self.setpoint_work()))
        n = self.g96 / r
        return float(min(n, self.g92)) if self.g92 > 0 else float(n)
