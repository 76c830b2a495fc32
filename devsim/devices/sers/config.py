"""Configuration of one simulated SERS: DIP switches, variant, parameters, axis geometry.

DIP switches (manual §3.1): switch 2 bits 1–7 = drive address (0 = master), bit 8 = autostart;
switch 1 bits 1–3 = baud rate, bits 4/5 = input level, bit 6 = service switch.  Variant codes
follow the type code "SERS cc.vv" (§1.2).  Geometry is in motor increments (12,800 per
revolution) measured from the power-on position.
"""

# No ``from __future__ import annotations`` here: msgspec reads a configuration's field types when
# the first one is parsed (every start), and types written as objects are read without the
# compile and eval of each string (about 6 M instructions of `devsim run sers`, issue 31).

import math
from typing import Annotated, Any, Literal

from devsim.core.settings import Check, Keys, Meta, Settings, doc, field
from devsim.devices.sers.paramdef import range_problem
from devsim.devices.sers.parameters import PARAMETER_TABLE

__all__ = ["AXIS_GEOMETRY", "AxisGeometry", "BAUD_RATES", "SersConfig"]

BAUD_RATES = (1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200)


def _known_parameter(key: Any) -> str:
    """A parameter named by number (``P1017``, ``1017``) or alias (``V``)."""
    if PARAMETER_TABLE.find(str(key)) is None:
        raise ValueError("no such parameter")
    return str(key)


def _param_range(key: str, number: float | int) -> float | int:
    """A value within the parameter's own range (§4.7), as the drive would check it."""
    pdef = PARAMETER_TABLE.lookup(key)
    if not math.isfinite(number):
        raise ValueError("not a finite number")
    if (problem := range_problem(pdef, number)) is not None:
        raise ValueError(problem)
    return number


def _baud(value: int) -> int:
    if value not in BAUD_RATES:
        raise ValueError(f"baud must be one of {', '.join(map(str, BAUD_RATES))}")
    return value


#: A switch position (increments), or None: no such switch.
_Position = float | None


class AxisGeometry(Settings):
    """Where the switches sit, in increments from the power-on position (§2.1.2)."""

    limit_left: Annotated[_Position, doc("left (negative) limit switch opens at and below this position")] = None
    limit_right: Annotated[_Position, doc("right (positive) limit switch opens at and above this position")] = None
    reference_low: Annotated[_Position, doc("reference cam start (switch active from here)")] = None
    reference_high: Annotated[_Position, doc("reference cam end (default: open-ended)")] = None
    index_offset: Annotated[float, doc("encoder index mark offset within a revolution")] = 0.0


#: Where the switches sit (the nested part ``axis``).
AXIS_GEOMETRY = AxisGeometry


class SersConfig(Settings):
    """What a user can set for one SERS (--config FILE.yaml or a plant file)."""

    address: Annotated[int, Meta(ge=0, le=127), doc("DIP switch 2 bits 1-7; 0 = master")] = 1
    autostart: Annotated[bool, doc("DIP switch 2 bit 8")] = False
    baud: Annotated[int, Check(_baud), doc("DIP switch 1 bits 1-3")] = 9600
    input_level: Annotated[Literal["plc", "ttl", "low_active", "invalid"], doc("DIP switch 1 bits 4/5")] = "plc"
    service_switch: Annotated[bool, doc("DIP switch 1 bit 6")] = False
    current_class: Literal["01", "02", "03", "04", "06", "08", "12"] = "06"
    supply_class: Literal["24", "60", "85", "120", "240"] = "85"
    options: list[Literal["E50", "IO", "P8", "RS485", "SERVO", "U"]] = []
    params: Annotated[dict[Any, float | int], Keys(_known_parameter, "parameter", entry=_param_range),
                      doc("factory/EEPROM parameter values, e.g. {P1017: 2, V: 500}")] = {}
    axis: AxisGeometry = field(default_factory=AxisGeometry)
    supply_voltage: Annotated[float | None, doc("initial supply voltage (default nominal)")] = None
    heatsink_temperature: float = 30.0
    initially_selected: Annotated[bool | None,
                                  doc("G-ADDR: selected after power-on (default: true unless on a shared line)")] = None
    broadcast_reply: Annotated[Literal["none", "lowest_address"],
                               doc("G-ADDR: who answers a broadcast (#*) line: none, or the drive with the lowest "
                                   "address on the line")] = "none"
    error_trailing_star: Annotated[bool, doc("G-ERRFMT: an error message has a '*' after its text too "
                                             "(*text*), as the manual's OCR example shows it")] = False
    ok_after_error: Annotated[bool, doc("G-ERRFMT: a line with an error is acknowledged (ok<d>) after its "
                                        "error message too")] = False
    counter_decrement_first: Annotated[bool, doc("G-COUNTER: a counter C1..C3 in IF is decremented before the "
                                                 "comparison (the manual's rule) instead of after it (its examples)")] = False
    i6_mode: Annotated[Literal["toggle", "level"], doc("G-INFUNC: input I6 switches the motor ON/OFF at each "
                                                       "rising edge (toggle), or ON while active (level)")] = "toggle"
    list_decimals: Annotated[Annotated[int, Meta(ge=0, le=6)] | None, doc(
        "G-LIST: decimals of a weighted constant in LIST (the manual's example V=500.000 has 3); "
        "None: all of the weighting's (V=500.0000)")] = None
    spontaneous_fault_messages: Annotated[bool, doc(
        "G-FAULTMSG: send '*<text>' (e.g. *Fehler Lagegrenzwert, *Vorwarnung Unterspannung) between lines "
        "when a drive error or an undervoltage/overtemperature warning is set")] = False
    query_units: Annotated[bool, doc("G-QUERYFMT: a query answer carries the unit (P51=2.5mm); false: "
                                     "the number alone (P51=2.5); also LISTP")] = True
    query_fixed_decimals: Annotated[bool, doc("G-QUERYFMT: a query answer keeps all decimals of the weighting "
                                              "(P51=2.500mm) instead of dropping trailing zeros; also LISTP")] = False
    query_name_style: Annotated[Literal["as_asked", "number"], doc(
        "G-QUERYFMT: a query answer names the parameter as asked (V?: V=...) or by number (V?: P91=...)")] = "as_asked"
    ack_each_terminator: Annotated[bool, doc("G-CRLF: the second half of a CR/LF (or LF/CR) pair is acknowledged "
                                             "too (two ok<d> for a line ending CR LF)")] = False
    boot_time: Annotated[float, Meta(ge=0), doc("seconds of display '-' after power-on (§3.5)")] = 2.0
    encoding: Literal["latin-1", "cp437"] = "latin-1"
