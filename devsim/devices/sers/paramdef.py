"""How a SERS parameter row is written (manual §4.7, §4.8); the rows are in ``params_*.py``.

Every row is a kit :class:`~devsim.core.parameters.Param`; :class:`Rows` spells one in the
manual's terms (``_p(number, German designation, English gloss, **facts)``) and puts the facts
only the SERS has into the row's ``extra`` (see :data:`EXTRA`).  See
:mod:`devsim.devices.sers.parameters` for the conventions of the table.
"""

from __future__ import annotations

from collections.abc import Iterable
from types import MappingProxyType
from typing import Any, Literal

from devsim.core.parameters import Param
from devsim.devices.sers.units import quantize

__all__ = ["EXTRA", "POS_MAX", "POS_MIN", "RW_E", "Kind", "Number", "Rows", "UNITS", "below_exclusive_minimum",
           "range_problem"]

#: How a value is kept and shown: a plain integer, a weighted quantity (converted with P76 /
#: P44 / P160, §4.8.4.6) or a number with a fixed number of decimals.
Kind = Literal["int", "position", "velocity", "acceleration", "fixed"]
Number = int | float

#: The unit column of a weighted parameter: its unit follows the weighting parameters.
UNITS: dict[str, str] = {"position": "P123 unit", "velocity": "P121 unit", "acceleration": "P122 unit"}

#: The SERS's own facts of a row (``Param.extra``) and their values when a row does not name them:
#: ``kind`` (:data:`Kind`); the errnos of a value too large, too small, not among the choices, and
#: of a write to a read-only parameter; ``min_exclusive`` for a range "> minimum" (V, P103, P123);
#: ``saved_with_p1117`` for W and R0..R5 (stored by PSAVE only with P1117=1); ``length_unit``
#: when the query answer carries the position length unit (P123); ``commands``, the command
#: keywords and bit addresses acting on the parameter; ``mode3_range``, the range that replaces
#: the row's own in positioning mode P1014=3 (C1, the signed overflow counter, §4.8.5.2);
#: ``note``, the manual's remarks.
EXTRA: dict[str, Any] = {
    "kind": "int",
    "too_large_errno": 1,
    "too_small_errno": 2,
    "invalid_errno": 3,
    "write_errno": 105,
    "min_exclusive": False,
    "saved_with_p1117": False,
    "length_unit": False,
    "commands": (),
    "mode3_range": None,
    "note": "",
}


def below_exclusive_minimum(row: Param, value: float) -> bool:
    """A value written to a row whose range is "> minimum" (V, P103, P123) is not above it as the
    drive keeps it: a fixed-point value on its grid (§4.7; ``P123=.00001`` is 0.0000)."""
    if not row.extra["min_exclusive"] or row.minimum is None:
        return False
    kept = quantize(float(value), row.decimals) if row.extra["kind"] == "fixed" else value
    return kept <= row.minimum


def range_problem(row: Param, value: float) -> str | None:
    """Why ``value`` (finite, in the unit the row's range is in) is outside the row's own range
    (§4.7), or None: not one of its choices, below its minimum, not above a "> minimum" as the
    drive keeps it, above its maximum.  (A configured value is checked with it, and a stored one.)"""
    if row.choices is not None and int(value) not in row.choices:
        return f"{value:g} is not one of {', '.join(map(str, sorted(row.choices)))}"
    if row.minimum is not None and value < row.minimum:
        return f"{value:g} is below the minimum {row.minimum:g}"
    if below_exclusive_minimum(row, value):  # (as the drive keeps it: P123 0.00001 is 0.0000)
        return f"{value:g} must be above {row.minimum:g}"
    if row.maximum is not None and value > row.maximum:
        return f"{value:g} is above the maximum {row.maximum:g}"
    return None


def _access(readable: bool, writable: bool) -> Literal["rw", "r", "w"]:
    return "rw" if readable and writable else "r" if readable else "w"


class Rows(list[Param]):
    """Collects the rows of one table module: ``_p(number, name, name_en, **facts)``.

    ``name`` is the German designation (the manual's heading, the answer to ``P<n>??``),
    ``name_en`` the English gloss (the answer with P265=1), the row's ``doc``."""

    def __call__(
        self,
        number: int,
        name: str,
        name_en: str,
        *,
        aliases: tuple[str, ...] = (),
        decimals: int = 0,
        minimum: Number | None = None,
        maximum: Number | None = None,
        choices: Iterable[int] | None = None,
        default: Number | None = 0,
        readable: bool = True,
        writable: bool = True,
        saved: bool = False,
        doc: str = "",
        attr: str = "",
        **facts: Any,
    ) -> None:
        unknown = set(facts) - set(EXTRA) - {"kind"}
        if unknown:  # pragma: no cover - table integrity
            raise TypeError(f"P{number}: unknown facts {sorted(unknown)}")
        kind = facts.get("kind", "int")
        extra = {**EXTRA, **facts, "note": doc}
        self.append(
            Param(
                number,
                name,
                f"§4.7 P{number}",
                name_en,
                aliases=aliases,
                type="int" if kind == "int" else "float",
                minimum=minimum,
                maximum=maximum,
                choices=None if choices is None else tuple(sorted(choices)),
                unit=UNITS.get(kind, ""),
                decimals=decimals,
                default=default,
                saved=saved,
                access=_access(readable, writable),
                attr=attr,
                extra=MappingProxyType(extra),
            )
        )


# Position range of W etc. in the default weighting (rotational, 4 decimals) -- §4.8.4.2.
POS_MIN, POS_MAX = -214748.3647, 214748.3647
RW_E: dict[str, Any] = {"saved": True}
