"""The shape of one SERS parameter row (manual §4.7, §4.8); the rows are in ``params_*.py``.

See :mod:`devsim.devices.sers.parameters` for the conventions of the table.
"""

from __future__ import annotations

from typing import Any, Literal

from devsim.core.record import record

__all__ = ["POS_MAX", "POS_MIN", "RW_E", "Kind", "Number", "ParamDef", "Rows"]

Kind = Literal["int", "position", "velocity", "acceleration", "fixed"]
Number = int | float


@record
class ParamDef:
    number: int
    name: str  # German designation (manual heading) -- returned by P<n>??
    name_en: str  # English gloss (P265=1)
    aliases: tuple[str, ...] = ()
    kind: Kind = "int"
    decimals: int = 0  # for kind "fixed"
    minimum: Number | None = None
    maximum: Number | None = None
    choices: frozenset[int] | None = None
    default: Number | None = 0
    readable: bool = True
    writable: bool = True
    saved: bool = False
    saved_with_p1117: bool = False
    too_large_errno: int = 1
    too_small_errno: int = 2
    doc: str = ""
    # --- extensions beyond the brief -----------------------------------------------------------
    min_exclusive: bool = False  # range is "> minimum"
    invalid_errno: int = 3  # value not in choices
    write_errno: int = 105  # write to a read-only parameter
    length_unit: bool = False  # query answer carries the position length unit (P123)
    commands: tuple[str, ...] = ()  # command keywords / bit addresses acting on this parameter

    @property
    def weighted(self) -> bool:
        return self.kind in ("position", "velocity", "acceleration")




class Rows(list[ParamDef]):
    """Collects the rows of one table module: ``_p(number, name, name_en, **fields)``."""

    def __call__(self, number: int, name: str, name_en: str, **kw: Any) -> None:
        self.append(ParamDef(number, name, name_en, **kw))


# Position range of W etc. in the default weighting (rotational, 4 decimals) -- §4.8.4.2.
POS_MIN, POS_MAX = -214748.3647, 214748.3647
RW_E: dict[str, Any] = {"saved": True}
