"""Where the PCD9.H3E1 library keeps each axis in the PLC's media (spec pcd4h3.md §4.1–§4.3):
the register block (20 registers per axis from BAR + RAi) and the flag field (35 flags per axis
from BAF + FAi), whose rows are :data:`~devsim.devices.pcd4h3.tables.REGISTERS` and
:data:`~devsim.devices.pcd4h3.tables.FLAG_FIELD`; the host reaches them over S-Bus.

Flag offsets 10 … 33 are the spec's reconstruction (G-1) and may be replaced by ``flag_map``
should the original H3DEF.SRC turn up.  Pure address arithmetic.
"""

from __future__ import annotations

from devsim.core.parameters import Param
from devsim.devices.pcd4h3.tables import FLAG_FIELD, REGISTERS, command_flags

__all__ = ["DIAG_FLAGS", "DIAG_REGISTERS", "FLAGS_PER_AXIS", "Layout", "REGISTERS_PER_AXIS"]

REGISTERS_PER_AXIS, FLAGS_PER_AXIS = len(REGISTERS), len(FLAG_FIELD)  # NoRfeA 20, NoFfeA 35 (§4.1)
DIAG_REGISTERS, DIAG_FLAGS = 16, 8  # the simulator's diagnostics block, per axis (spec §9.6.3)


class Layout:
    """The media addresses of an installation (§4.1: BAR, BAF; RAi = (i−1)·20, FAi = (i−1)·35)."""

    def __init__(self, bar: int = 2000, baf: int = 2000, axes: int = 2, flag_map: dict[str, int] | None = None) -> None:
        self.bar, self.baf, self.axes = bar, baf, axes
        self.flag_offsets = {row.name: int(row.key) for row in FLAG_FIELD} | dict(flag_map or {})
        #: The command flags in the order AxHndlg scans them: by offset (§3.3.2).
        self.command_order = tuple(sorted((row.name for row in command_flags()),
                                          key=lambda symbol: self.flag_offsets[symbol]))

    def block(self, axis: int) -> int:
        """BAR + RAi: the first register of axis ``axis``'s block."""
        return self.bar + (axis - 1) * REGISTERS_PER_AXIS

    def register(self, axis: int, symbol: str) -> int:
        return self.block(axis) + int(REGISTERS.lookup(symbol, "the register block").key)

    def flag(self, axis: int, symbol: str) -> int:
        return self.baf + (axis - 1) * FLAGS_PER_AXIS + self.flag_offsets[symbol]

    def locate_register(self, address: int) -> tuple[int, Param] | None:
        """(axis, register row) of a register address, or None outside the blocks."""
        index = address - self.bar
        if not 0 <= index < self.axes * REGISTERS_PER_AXIS:
            return None
        return index // REGISTERS_PER_AXIS + 1, REGISTERS[index % REGISTERS_PER_AXIS]

    def locate_flag(self, address: int) -> tuple[int, str] | None:
        """(axis, flag symbol) of a flag address, or None outside the fields."""
        index = address - self.baf
        if not 0 <= index < self.axes * FLAGS_PER_AXIS:
            return None
        offset = index % FLAGS_PER_AXIS
        symbol = next((s for s, o in self.flag_offsets.items() if o == offset), None)
        return (index // FLAGS_PER_AXIS + 1, symbol) if symbol is not None else None
