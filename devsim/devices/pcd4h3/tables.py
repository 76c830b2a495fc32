"""The rows of an axis's media in the PCD (spec pcd4h3.md §4.2, §4.3; manual §7.1.5, §7.4,
§10.1): the register block, the kind's parameters, and the flag field, both as kit rows
(:class:`~devsim.core.parameters.Param`) keyed by their offset in the block or field.

A register's ``name`` is its H3DEF symbol (``DestP``), which is also an alias: the PCD
assembler is case-insensitive (§7.1.5), so ``REGISTERS.find("destp")`` finds offset 7.  The
register's direction (§4.2: a *load* register is written by the user and read by the functions,
a *read* register written by a read function) is ``extra["direction"]``.  The simulator's
initial contents are the manual's Example 1 (G-16), the read registers 0.

A flag's ``extra["kind"]`` is ``status``, ``parameter`` or ``command``; a command flag names a
library function (§3.2), whose execution time in the PLC (§10.1) is ``extra["time_ms"]`` and
whether it may run during a motion ``extra["in_motion"]``.  Flag offsets 10 … 33 are the spec's
reconstruction (G-1), replaceable by the configuration's ``flag_map``.  Pure tables.
"""

from __future__ import annotations

from typing import Any

from devsim.core.parameters import Param, ParameterTable
from devsim.core.words import signed32

__all__ = ["FLAG_FIELD", "REGISTERS", "command_flags", "flag_row", "load_registers"]


def _register(offset: int, symbol: str, doc: str, direction: str, attr: str, *, minimum: int | None = None,
              maximum: int | None = None, unit: str = "", default: int = 0) -> Param:
    return Param(offset, symbol, "§4.2", doc, (symbol,), minimum=minimum, maximum=maximum, unit=unit,
                 default=default, attr=attr, extra={"direction": direction})


REGISTERS = ParameterTable([
    _register(0, "KProp", "proportional factor", "load", "proportional", minimum=0, maximum=32767, default=150),
    _register(1, "KInt", "integral factor", "load", "integral", minimum=0, maximum=32767, default=50),
    _register(2, "KDer", "derivative factor", "load", "derivative", minimum=0, maximum=32767, default=50),
    _register(3, "IntL", "integration limit", "load", "integration_limit", minimum=0, maximum=32767, default=500),
    _register(4, "SampI", "D-part sample time n: (n+1)·341.33 µs", "load", "sample_interval", minimum=0,
              maximum=255, default=15),
    _register(5, "MCFac", "machine factor k (FFP float), counts per user unit", "load", "machine_factor",
              unit="FFP", default=signed32(0xC8000047)),
    _register(6, "PosEr", "position error limit", "load", "position_error_limit", minimum=0, maximum=32767,
              unit="counts", default=2000),
    _register(7, "DestP", "target position", "load", "destination", unit="user unit", default=1000),
    _register(8, "BrkP", "break position", "load", "break_position", unit="user unit", default=700),
    _register(9, "Veloc", "velocity", "load", "velocity", unit="user unit/s", default=500),
    _register(10, "Accel", "acceleration", "load", "acceleration", unit="user unit/s²", default=100),
    _register(11, "StaFRR", "status flag reset register", "load", "status_reset"),
    _register(12, "MCW", "motion control word", "load", "control_word", default=0x41B),
    _register(13, "RActP", "actual position", "read", "actual_position", unit="user unit"),
    _register(14, "RSetP", "set position", "read", "set_position", unit="user unit"),
    _register(15, "RActV", "actual velocity", "read", "actual_velocity", unit="user unit/s"),
    _register(16, "RSetV", "set velocity", "read", "set_velocity", unit="user unit/s"),
    _register(17, "RIndP", "index position", "read", "index_position", unit="user unit"),
    _register(18, "RIntTS", "integration sum", "read", "integration_sum"),
    _register(19, "RSigB", "signal register", "read", "signal_register"),
], name="register")
"""The register block of one axis (§4.2): 20 × 32-bit PCD registers from BAR + RAi."""


def _flag(offset: int, symbol: str, kind: str, doc: str, time_ms: float = 0.0, *, in_motion: bool = True) -> Param:
    extra: dict[str, Any] = {"kind": kind}
    if kind == "command":
        extra |= {"time_ms": time_ms, "in_motion": in_motion}
    return Param(offset, symbol, "§4.3", doc, (symbol,), type="bool", default=0, saved=False, extra=extra)


FLAG_FIELD = ParameterTable([
    _flag(0, "OnDest", "status", "target reached / trajectory complete"),
    _flag(1, "IPuls", "status", "index pulse captured"),
    _flag(2, "WrapOc", "status", "position register wrap-around"),
    _flag(3, "ExcPEr", "status", "excessive position error"),
    _flag(4, "BrkPos", "status", "break position reached"),
    _flag(5, "DplM", "parameter", "display mode for PCA2.D14 (0: 1×10, 1: 2×6 digits)"),
    _flag(6, "FLdDR", "command", "load target relative", 4.1),
    _flag(7, "FLdDA", "command", "load target absolute", 4.1),
    _flag(8, "FLdVR", "command", "load velocity relative", 4.5),
    _flag(9, "FLdVA", "command", "load velocity absolute", 4.5),
    _flag(10, "FLdAR", "command", "load acceleration relative (motor off while moving)", 7.2),
    _flag(11, "FLdAA", "command", "load acceleration absolute (motor off while moving)", 7.2),
    _flag(12, "FLdRP", "command", "load regulator parameters", 5.2),
    _flag(13, "FUpDRP", "command", "activate regulator parameters", 0.9),
    _flag(14, "FSelOM", "command", "select operating mode (MCW bits 11, 12)", 1.9),
    _flag(15, "FSetPE", "command", "define position error (MCW low byte 1Ah stop / 1Bh flag)", 1.9),
    _flag(16, "FResSF", "command", "reset status flags (StaFRR)", 1.8),
    _flag(17, "FLdBPR", "command", "load break position relative", 3.3),
    _flag(18, "FLdBPA", "command", "load break position absolute", 3.3),
    _flag(19, "FSetIP", "command", "capture index position", 0.9),
    _flag(20, "FSetZP", "command", "set zero position", 0.9),
    _flag(21, "FRdAP", "command", "read actual position", 4.3),
    _flag(22, "FRdSP", "command", "read set position", 4.3),
    _flag(23, "FRdAV", "command", "read actual velocity", 2.8),
    _flag(24, "FRdSV", "command", "read set velocity", 3.7),
    _flag(25, "FRdITS", "command", "read integration sum", 1.9),
    _flag(26, "FRdIP", "command", "read index position", 4.3),
    _flag(27, "FRdSR", "command", "read signal register", 1.8),
    _flag(28, "FStart", "command", "start motion / take over new parameters", 1.0),
    _flag(29, "FStop", "command", "stop motion (MCW bits 8 … 10)", 2.7),
    _flag(30, "FMotOff", "command", "control off", 1.8),
    _flag(31, "FSStepF", "command", "single step forward", 4.5, in_motion=False),
    _flag(32, "FSStepB", "command", "single step backward", 4.5, in_motion=False),
    _flag(33, "FForw", "command", "forward with defined velocity", 4.5),
    _flag(34, "FBackw", "command", "backward with defined velocity", 4.5),
], name="flag")
"""The flag field of one axis (§4.3): 35 flags from BAF + FAi."""


def flag_row(symbol: str) -> Param:
    """The flag ``symbol`` (any case)."""
    return FLAG_FIELD.lookup(symbol, "the flag field")


def command_flags() -> tuple[Param, ...]:
    """The command flags, in the table's (the manual's) offset order."""
    return tuple(row for row in FLAG_FIELD if row.extra["kind"] == "command")


def load_registers() -> tuple[Param, ...]:
    """The registers the user loads (§4.2 direction ``load``)."""
    return tuple(row for row in REGISTERS if row.extra["direction"] == "load")
