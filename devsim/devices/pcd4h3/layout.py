"""Where the PCD9.H3E1 library keeps each axis in the PLC's media (spec pcd4h3.md §3.2, §4.1–
§4.3): the register block (20 registers per axis from BAR + RAi) and the flag field (35 flags
per axis from BAF + FAi), declared once as tables; the host reaches them over S-Bus.

Flag offsets 10 … 33 are the spec's reconstruction (G-1) and may be replaced by ``flag_map``
should the original H3DEF.SRC turn up.  Pure tables and address arithmetic.
"""

from __future__ import annotations

from devsim.core.record import record
from devsim.core.words import signed32

__all__ = ["FLAGS", "Flag", "Layout", "REGISTERS", "Register", "FLAGS_PER_AXIS", "REGISTERS_PER_AXIS"]

REGISTERS_PER_AXIS, FLAGS_PER_AXIS = 20, 35  # NoRfeA, NoFfeA (§4.1)


@record
class Register:
    """One register of an axis block (§4.2)."""

    offset: int
    symbol: str
    meaning: str
    load: bool  # written by the user (False: written by a read function)
    minimum: int | None = None
    maximum: int | None = None
    unit: str = ""
    example: int = 0  # Example 1 of the manual, the simulator's initial contents (G-16)


@record
class Flag:
    """One flag of an axis field (§4.3); a command flag names its function (§3.2)."""

    offset: int
    symbol: str
    kind: str  # "status", "parameter" or "command"
    meaning: str
    time_ms: float = 0.0  # execution time in the PLC (§10.1)
    in_motion: bool = True  # executable during motion


REGISTERS: tuple[Register, ...] = (
    Register(0, "KProp", "proportional factor", True, 0, 32767, "", 150),
    Register(1, "KInt", "integral factor", True, 0, 32767, "", 50),
    Register(2, "KDer", "derivative factor", True, 0, 32767, "", 50),
    Register(3, "IntL", "integration limit", True, 0, 32767, "", 500),
    Register(4, "SampI", "D-part sample time n: (n+1)·341.33 µs", True, 0, 255, "", 15),
    Register(5, "MCFac", "machine factor k (FFP float), counts per user unit", True, unit="FFP",
             example=signed32(0xC8000047)),
    Register(6, "PosEr", "position error limit", True, 0, 32767, "counts", 2000),
    Register(7, "DestP", "target position", True, unit="user unit", example=1000),
    Register(8, "BrkP", "break position", True, unit="user unit", example=700),
    Register(9, "Veloc", "velocity", True, unit="user unit/s", example=500),
    Register(10, "Accel", "acceleration", True, unit="user unit/s²", example=100),
    Register(11, "StaFRR", "status flag reset register", True, example=0),
    Register(12, "MCW", "motion control word", True, example=0x41B),
    Register(13, "RActP", "actual position", False, unit="user unit"),
    Register(14, "RSetP", "set position", False, unit="user unit"),
    Register(15, "RActV", "actual velocity", False, unit="user unit/s"),
    Register(16, "RSetV", "set velocity", False, unit="user unit/s"),
    Register(17, "RIndP", "index position", False, unit="user unit"),
    Register(18, "RIntTS", "integration sum", False),
    Register(19, "RSigB", "signal register", False),
)

FLAGS: tuple[Flag, ...] = (
    Flag(0, "OnDest", "status", "target reached / trajectory complete"),
    Flag(1, "IPuls", "status", "index pulse captured"),
    Flag(2, "WrapOc", "status", "position register wrap-around"),
    Flag(3, "ExcPEr", "status", "excessive position error"),
    Flag(4, "BrkPos", "status", "break position reached"),
    Flag(5, "DplM", "parameter", "display mode for PCA2.D14 (0: 1×10, 1: 2×6 digits)"),
    Flag(6, "FLdDR", "command", "load target relative", 4.1),
    Flag(7, "FLdDA", "command", "load target absolute", 4.1),
    Flag(8, "FLdVR", "command", "load velocity relative", 4.5),
    Flag(9, "FLdVA", "command", "load velocity absolute", 4.5),
    Flag(10, "FLdAR", "command", "load acceleration relative (motor off while moving)", 7.2),
    Flag(11, "FLdAA", "command", "load acceleration absolute (motor off while moving)", 7.2),
    Flag(12, "FLdRP", "command", "load regulator parameters", 5.2),
    Flag(13, "FUpDRP", "command", "activate regulator parameters", 0.9),
    Flag(14, "FSelOM", "command", "select operating mode (MCW bits 11, 12)", 1.9),
    Flag(15, "FSetPE", "command", "define position error (MCW low byte 1Ah stop / 1Bh flag)", 1.9),
    Flag(16, "FResSF", "command", "reset status flags (StaFRR)", 1.8),
    Flag(17, "FLdBPR", "command", "load break position relative", 3.3),
    Flag(18, "FLdBPA", "command", "load break position absolute", 3.3),
    Flag(19, "FSetIP", "command", "capture index position", 0.9),
    Flag(20, "FSetZP", "command", "set zero position", 0.9),
    Flag(21, "FRdAP", "command", "read actual position", 4.3),
    Flag(22, "FRdSP", "command", "read set position", 4.3),
    Flag(23, "FRdAV", "command", "read actual velocity", 2.8),
    Flag(24, "FRdSV", "command", "read set velocity", 3.7),
    Flag(25, "FRdITS", "command", "read integration sum", 1.9),
    Flag(26, "FRdIP", "command", "read index position", 4.3),
    Flag(27, "FRdSR", "command", "read signal register", 1.8),
    Flag(28, "FStart", "command", "start motion / take over new parameters", 1.0),
    Flag(29, "FStop", "command", "stop motion (MCW bits 8 … 10)", 2.7),
    Flag(30, "FMotOff", "command", "control off", 1.8),
    Flag(31, "FSStepF", "command", "single step forward", 4.5, in_motion=False),
    Flag(32, "FSStepB", "command", "single step backward", 4.5, in_motion=False),
    Flag(33, "FForw", "command", "forward with defined velocity", 4.5),
    Flag(34, "FBackw", "command", "backward with defined velocity", 4.5),
)


class Layout:
    """The media addresses of an installation (§4.1: BAR, BAF; RAi = (i−1)·20, FAi = (i−1)·35)."""

    def __init__(self, bar: int = 2000, baf: int = 2000, axes: int = 2, flag_map: dict[str, int] | None = None) -> None:
        self.bar, self.baf, self.axes = bar, baf, axes
        self.flag_offsets = {f.symbol: f.offset for f in FLAGS} | dict(flag_map or {})
        self.register_offsets = {r.symbol: r.offset for r in REGISTERS}
        #: The command flags in the order AxHndlg scans them: by offset (§3.3.2).
        self.command_order = tuple(sorted((f.symbol for f in FLAGS if f.kind == "command"),
                                          key=lambda symbol: self.flag_offsets[symbol]))

    def register(self, axis: int, symbol: str) -> int:
        return self.bar + (axis - 1) * REGISTERS_PER_AXIS + self.register_offsets[symbol]

    def flag(self, axis: int, symbol: str) -> int:
        return self.baf + (axis - 1) * FLAGS_PER_AXIS + self.flag_offsets[symbol]

    def locate_register(self, address: int) -> tuple[int, Register] | None:
        """(axis, register) of a register address, or None outside the blocks."""
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
