"""Configuration of one simulated SERS: DIP switches, variant, parameters, axis geometry.

DIP switches (manual §3.1): switch 2 bits 1–7 = drive address (0 = master), bit 8 = autostart;
switch 1 bits 1–3 = baud rate, bits 4/5 = input level, bit 6 = service switch.  Variant codes
follow the type code "SERS cc.vv" (§1.2).  Geometry is in motor increments (12,800 per
revolution) measured from the power-on position.
"""

from __future__ import annotations

import math
from typing import Any

from devsim.core.settings import Bool, DictOf, Float, Int, ListOf, Maybe, OneOf, Section, Setting
from devsim.devices.sers.parameters import lookup

__all__ = ["AXIS_GEOMETRY", "BAUD_RATES", "SersConfig"]

BAUD_RATES = (1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200)


def _known_parameter(key: Any) -> str:
    """A parameter named by number (``P1017``, ``1017``) or alias (``V``)."""
    try:
        lookup(str(key))
    except KeyError:
        raise ValueError("no such parameter") from None
    return str(key)


def _param_ranges(value: dict[str, float | int]) -> dict[str, float | int]:
    """Each value within the parameter's own range (§4.7), as the drive would check it."""
    for key, number in value.items():
        pdef = lookup(key)
        if not math.isfinite(number):
            raise ValueError(f"{key}: not a finite number")
        if pdef.choices is not None and int(number) not in pdef.choices:
            raise ValueError(f"{key}: {number:g} is not one of {', '.join(map(str, sorted(pdef.choices)))}")
        if pdef.minimum is not None and number < pdef.minimum:
            raise ValueError(f"{key}: {number:g} is below the minimum {pdef.minimum:g}")
        if pdef.min_exclusive and pdef.minimum is not None and number <= pdef.minimum:
            raise ValueError(f"{key}: {number:g} must be above {pdef.minimum:g}")
        if pdef.maximum is not None and number > pdef.maximum:
            raise ValueError(f"{key}: {number:g} is above the maximum {pdef.maximum:g}")
    return value


def _baud(value: int) -> int:
    if value not in BAUD_RATES:
        raise ValueError(f"baud must be one of {', '.join(map(str, BAUD_RATES))}")
    return value


_POSITION = Maybe(Float())

#: Where the switches sit, in increments from the power-on position (§2.1.2).
AXIS_GEOMETRY = Section("Where the switches sit, in increments from the power-on position (§2.1.2).", (
    Setting("limit_left", _POSITION, None, "left (negative) limit switch opens at and below this position"),
    Setting("limit_right", _POSITION, None, "right (positive) limit switch opens at and above this position"),
    Setting("reference_low", _POSITION, None, "reference cam start (switch active from here)"),
    Setting("reference_high", _POSITION, None, "reference cam end (default: open-ended)"),
    Setting("index_offset", Float(), 0.0, "encoder index mark offset within a revolution"),
))

#: What a user can set for one SERS (``--config FILE.yaml`` or a plant file).
SersConfig = Section("What a user can set for one SERS (--config FILE.yaml or a plant file).", (
    Setting("address", Int(ge=0, le=127), 1, "DIP switch 2 bits 1-7; 0 = master"),
    Setting("autostart", Bool(), False, "DIP switch 2 bit 8"),
    Setting("baud", Int(), 9600, "DIP switch 1 bits 1-3", check=_baud),
    Setting("input_level", OneOf("plc", "ttl", "low_active", "invalid"), "plc", "DIP switch 1 bits 4/5"),
    Setting("service_switch", Bool(), False, "DIP switch 1 bit 6"),
    Setting("current_class", OneOf("01", "02", "03", "04", "06", "08", "12"), "06"),
    Setting("supply_class", OneOf("24", "60", "85", "120", "240"), "85"),
    Setting("options", ListOf(OneOf("E50", "IO", "P8", "RS485", "SERVO", "U")), []),
    Setting("params", DictOf(_known_parameter, Float(integers=True), "parameter"), {},
            "factory/EEPROM parameter values, e.g. {P1017: 2, V: 500}", check=_param_ranges),
    Setting("axis", AXIS_GEOMETRY, {}),
    Setting("supply_voltage", Maybe(Float()), None, "initial supply voltage (default nominal)"),
    Setting("heatsink_temperature", Float(), 30.0),
    Setting("initially_selected", Maybe(Bool()), None,
            "G-ADDR: selected after power-on (default: true unless on a shared line)"),
    Setting("broadcast_reply", OneOf("none", "lowest_address"), "none"),
    Setting("boot_time", Float(ge=0), 2.0, "seconds of display '-' after power-on (§3.5)"),
    Setting("encoding", OneOf("latin-1", "cp437"), "latin-1"),
))
