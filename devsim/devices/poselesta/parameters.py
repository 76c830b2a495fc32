"""The machine parameters the host link depends on (manual §2.4.9, §2.6.2, §2.6.3; spec
poselesta.md §4.8).  Every number P1 … P98 is stored (default 0) and round-trips; these have a
declared range and an effect: on the serial ports, the buzzer, the strobes, the speeds and gains
of the axes and the NC-Start."""

from __future__ import annotations

import math

from devsim.core.record import record
from devsim.devices.poselesta.tape import Block

__all__ = ["PARAMETERS", "ParamDef", "catalogue_blocks", "check_parameter", "store_parameter"]

#: The catalogue's value word P carries 3 decimals (spec §3.9, simulator-defined format).
CATALOGUE_SCALE = 1000


@record
class ParamDef:
    number: int
    name: str
    minimum: float
    maximum: float
    default: float
    section: str
    whole: bool = True  # only whole numbers (a code, a count, a speed)
    choices: tuple[int, ...] | None = None


PARAMETERS: dict[int, ParamDef] = {
    p.number: p
    for p in (
        ParamDef(1, "measuring system of the catalogues (0 = mm, 1 = inch)", 0, 1, 0, "§2.3.14"),
        ParamDef(67, "buzzer V16/6 (0 = on, 1 = off)", 0, 1, 0, "§2.4.9"),
        ParamDef(68, "V6 baud rate code (0 = 110 … 5 = 4800)", 0, 5, 3, "§2.6.2.3"),
        ParamDef(69, "V6 code (0 = ISO, 1 = ASCII)", 0, 1, 0, "§2.6.2.1–3"),
        ParamDef(70, "V7 baud rate code (0 = 110 … 5 = 4800)", 0, 5, 3, "§2.6.3"),
        ParamDef(71, "V7 code (0 = ISO, 1 = ASCII)", 0, 1, 0, "§2.6.3"),
        ParamDef(72, "strobe times t1 = t2 in ms (0 is taken as 1 ms)", 0, 99, 20, "§2.4.7"),
        *(ParamDef(9 + i, f"software limit + {a}, mm from the reference mark", -99999, 99999, 99999, "§2.4.4",
                   False)
          for i, a in enumerate("XYZD")),
        *(ParamDef(13 + i, f"software limit − {a}, mm from the reference mark", -99999, 99999, -99999, "§2.4.4",
                   False)
          for i, a in enumerate("XYZD")),
        *(ParamDef(30 + i, f"gain (Verstärkung) {a}: Kv = P{30 + i} × kv_per_step", 1, 99, 10, "§2.5")
          for i, a in enumerate("XYZD")),
        *(ParamDef(44 + i, f"maximum speed = rapid {a}, mm/min (G00, V21/6)", 0, 9999, 6000, "§2.3.8")
          for i, a in enumerate("XYZD")),
        *(ParamDef(48 + i, f"maximum feed {a}, mm/min (100 % of the feed pot)", 0, 9999, 2000, "§2.3.6")
          for i, a in enumerate("XYZD")),
        ParamDef(64, "rapid influenced by the override pot (0 = no, 1 = yes)", 0, 1, 0, "§2.3.22"),
        ParamDef(75, "NC-Start source (0 = both, 1 = front panel, 2 = external V19/3)", 0, 2, 0, "§2.3.3"),
        ParamDef(76, "handwheel evaluation: increments per handwheel step (1, 2 or 4)", 1, 4, 1, "§2.2.3",
                 choices=(1, 2, 4)),
        ParamDef(77, "open-loop axes, bit mask X = 1, Y = 2, Z = 4, D = 8", 0, 15, 0, "§2.3.9"),
        ParamDef(90, "block number N the program goes on at after a block abort V22/10 (POS III)", 0, 999, 0,
                 "§2.3.21"),
    )
}


def check_parameter(number: int, value: float) -> None:
    """Refuse a parameter number or value the control would not take (ValueError)."""
    if not 1 <= number <= 98 or number == 79:
        raise ValueError(f"P{number}: parameters are P1 … P98 (P79 is the diagnostic program)")
    if not math.isfinite(value):
        raise ValueError(f"P{number}: not a finite number")
    pdef = PARAMETERS.get(number)
    if pdef is not None:
        if not pdef.minimum <= value <= pdef.maximum or pdef.whole and not float(value).is_integer():
            kind = "a whole number" if pdef.whole else "a number"
            raise ValueError(f"P{number}: {value:g} is not {kind} in {pdef.minimum:g} … {pdef.maximum:g}")
        if pdef.choices is not None and value not in pdef.choices:
            raise ValueError(f"P{number}: {value:g} is not one of {', '.join(map(str, pdef.choices))}")


def catalogue_blocks(params: dict[int, float]) -> list[Block]:
    """The machine-parameter catalogue P99 as blocks ``N<number> P<value>``, P1 … P98 without
    P79 (spec §3.9, a simulator-defined format: the original is not documented)."""
    return [Block(number, (("P", round(params.get(number, 0.0) * CATALOGUE_SCALE)),))
            for number in range(1, 99) if number != 79]


def store_parameter(pending: dict[int, float], block: Block) -> str | None:
    """A catalogue block read in: N selects the parameter, P is its value (unknown numbers are
    kept); returns why it cannot be taken (the read-in then fails), or None."""
    value = block.value("P")
    if value is None:
        return None  # a block without a value changes nothing
    try:
        check_parameter(block.number, value / CATALOGUE_SCALE)
    except ValueError as exc:
        return str(exc)
    pending[block.number] = value / CATALOGUE_SCALE
    return None
