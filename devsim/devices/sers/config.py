"""Configuration of one simulated SERS: DIP switches, variant, parameters, axis geometry.

DIP switches (manual §3.1): switch 2 bits 1–7 = drive address (0 = master), bit 8 = autostart;
switch 1 bits 1–3 = baud rate, bits 4/5 = input level, bit 6 = service switch.  Variant codes
follow the type code "SERS cc.vv" (§1.2).  Geometry is in motor increments (12,800 per
revolution) measured from the power-on position.
"""

from __future__ import annotations

import math
from typing import Annotated, Literal

from pydantic import AfterValidator, BaseModel, ConfigDict, Field, field_validator

from devsim.devices.sers.parameters import lookup

__all__ = ["AxisGeometry", "SersConfig"]

BAUD_RATES = (1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200)


def _known_parameter(key: str) -> str:
    try:
        lookup(str(key))
    except KeyError:
        raise ValueError("no such parameter") from None
    return key


#: A parameter named by number (``P1017``, ``1017``) or alias (``V``).
ParamKey = Annotated[str, AfterValidator(_known_parameter)]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid")


class AxisGeometry(_Strict):
    """Where the switches sit, in increments from the power-on position (§2.1.2)."""

    limit_left: float | None = Field(
        default=None, description="left (negative) limit switch opens at and below this position"
    )
    limit_right: float | None = Field(
        default=None, description="right (positive) limit switch opens at and above this position"
    )
    reference_low: float | None = Field(default=None, description="reference cam start (switch active from here)")
    reference_high: float | None = Field(default=None, description="reference cam end (default: open-ended)")
    index_offset: float = Field(default=0.0, description="encoder index mark offset within a revolution")


class SersConfig(_Strict):
    """What a user can set for one SERS (``--config FILE.yaml`` or a plant file)."""

    address: int = Field(default=1, ge=0, le=127, description="DIP switch 2 bits 1-7; 0 = master")
    autostart: bool = Field(default=False, description="DIP switch 2 bit 8")
    baud: int = Field(default=9600, description="DIP switch 1 bits 1-3")
    input_level: Literal["plc", "ttl", "low_active", "invalid"] = Field(
        default="plc", description="DIP switch 1 bits 4/5"
    )
    service_switch: bool = Field(default=False, description="DIP switch 1 bit 6")
    current_class: Literal["01", "02", "03", "04", "06", "08", "12"] = "06"
    supply_class: Literal["24", "60", "85", "120", "240"] = "85"
    options: list[Literal["E50", "IO", "P8", "RS485", "SERVO", "U"]] = Field(default_factory=list)
    params: dict[ParamKey, float | int] = Field(
        default_factory=dict, description="factory/EEPROM parameter values, e.g. {P1017: 2, V: 500}"
    )
    axis: AxisGeometry = Field(default_factory=AxisGeometry)
    supply_voltage: float | None = Field(default=None, description="initial supply voltage (default nominal)")
    heatsink_temperature: float = 30.0
    initially_selected: bool | None = Field(
        default=None, description="G-ADDR: selected after power-on (default: true unless on a shared line)"
    )
    broadcast_reply: Literal["none", "lowest_address"] = "none"
    boot_time: float = Field(default=2.0, ge=0, description="seconds of display '-' after power-on (§3.5)")
    encoding: Literal["latin-1", "cp437"] = "latin-1"

    @field_validator("params")
    @classmethod
    def _param_ranges(cls, value: dict[str, float | int]) -> dict[str, float | int]:
        """Each value within the parameter's own range (§4.7), as the drive would check it."""
        for key, number in value.items():
            pdef = lookup(key)
            if not math.isfinite(number):
                raise ValueError(f"{key}: not a finite number")
            if pdef.choices is not None and int(number) not in pdef.choices:
                raise ValueError(f"{key}: {number:g} is not one of {', '.join(map(str, sorted(pdef.choices)))}")
            if pdef.minimum is not None and number < pdef.minimum:
                raise ValueError(f"{key}: {number:g} is below the minimum {pdef.minimum:g}")
            if pdef.maximum is not None and number > pdef.maximum:
                raise ValueError(f"{key}: {number:g} is above the maximum {pdef.maximum:g}")
        return value

    @field_validator("baud")
    @classmethod
    def _baud(cls, value: int) -> int:
        if value not in BAUD_RATES:
            raise ValueError(f"baud must be one of {', '.join(map(str, BAUD_RATES))}")
        return value
