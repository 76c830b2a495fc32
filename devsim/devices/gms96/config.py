"""Configuration of one simulated GMS96 card (spec gms96.md §2.2, Appendix A).

DIL switch (manual §2.2): address 0..31 (switches 1..4 inverted + switch 5 = +16), switch 6
interpolation, switch 7 protocol S/E, switch 8 baud 9600/38400.  The switch is read only at
power-on or after a reset (emergency-stop release).  Axis geometry is in increments from the
power-on position: reference cam, index marks, mechanical end stops and optional position
ranges wired to inputs (the GMS has no limit-switch inputs of its own, spec §5.11).
"""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from devsim.devices.gms96.tables import INT24_MAX, INT24_MIN, N_PARAMETERS

__all__ = [
    "AxisGeometry",
    "DilSwitch",
    "Gms96Config",
    "LimitSwitch",
    "LinkOptions",
    "PlcCopyRule",
    "PlcFaultMessages",
    "PlcLimitRule",
    "PlcOptions",
    "PlcStartRule",
]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid")


class DilSwitch(_Strict):
    """The 8-position DIL switch (manual §2.2), as its meaning rather than switch positions."""

    address: int = Field(default=3, ge=0, le=31, description="switches 1..4 (+16 with switch 5)")
    interpolation: bool = Field(default=False, description="switch 6: behind a GMS-I card")
    protocol: Literal["S", "E"] = Field(default="S", description="switch 7: DIN 19244 S- or E-version")
    baud: Literal[9600, 38400] = Field(default=9600, description="switch 8")


class LimitSwitch(_Strict):
    """A position range that drives an input bit (spec §5.11 a); the PLC decides what it means."""

    input: str = Field(description="input bit, e.g. E0.3")
    low: float | None = Field(default=None, description="active from here (None: -inf)")
    high: float | None = Field(default=None, description="active up to here (None: +inf)")


class AxisGeometry(_Strict):
    """Where things sit on the axis, in increments from the power-on position (spec §5.6)."""

    cam: tuple[float, float] | None = Field(
        default=(-20000.0, -15000.0), description="reference cam [low, high] or null (no cam)"
    )
    cam_input: Literal["E2.1", "E2.0"] = "E2.1"
    cam_polarity: Literal["NO", "NC"] = Field(default="NO", description="NO: 24 V while on the cam")
    index_period: int = Field(default=4096, gt=0, description="increments between index marks (counts/rev)")
    index_offset: float = 0.0
    counter_marks: list[float] = Field(
        default_factory=list, description="reference marks of the counter input's scale (Q with P2.5)"
    )
    end_stops: tuple[float, float] | None = Field(default=None, description="mechanical end stops [low, high]")
    limit_switches: list[LimitSwitch] = Field(default_factory=list)
    kv_per_n10: float = Field(default=0.2, gt=0, description="Kv [1/s] per unit of N10 (spec §5.7)")
    position_after_reset: Literal["zero", "keep"] = "zero"
    brake_stop_ms: float = Field(default=50.0, ge=0)
    i2t_t_allow_s: float = Field(default=2.0, gt=0)


class LinkOptions(_Strict):
    """Link-layer choices the manual leaves open (spec §3.7, §3.9, Appendix A)."""

    response_delay: float = Field(default=0.0, ge=0, le=0.1, description="seconds before a reply")
    char_timeout: float = Field(default=0.05, gt=0, description="inter-character timeout (s)")
    unknown_command_reply: Literal["ack", "none"] = "ack"
    unknown_short_command_reply: Literal["ack", "none"] = "ack"
    on_queue_full: Literal["defer", "drop", "nack"] = "defer"
    e_version_features: list[Literal["fcb", "acd", "dfc"]] = Field(default_factory=lambda: ["fcb", "acd", "dfc"])
    broadcast_address: int | None = Field(default=None, description="e.g. 255; None = no broadcast")
    error_line_idle: bool = Field(
        default=True,
        description="FT1.2 rule R4: after a detected frame error accept a new frame only after >= 33 bit "
        "times of line idle (False: resynchronise at once)",
    )


class PlcLimitRule(_Strict):
    """Limit-switch rule (spec §4.10.3, §5.11): an input → STOP (M0.0) or abort (M0.1) + message.

    ``stop``: M0.0 follows the switch (set while active, released when it clears, so the
    interrupted move continues).  ``abort``: M0.1 is pulsed on the active edge, and again every
    cycle while the switch is active and the axis is commanded towards ``direction``, so the
    axis can always be driven back out of the switch."""

    input: str = Field(description="input bit, e.g. E0.3")
    action: Literal["stop", "abort"] = "abort"
    message: int = Field(default=0, ge=0, le=255, description="code into MB4 on the active edge (0 = none)")
    active_low: bool = Field(default=False, description="normally-closed switch: active at 0 V")
    direction: Literal["+", "-", "any"] = Field(default="any", description="only act on motion this way")


class PlcFaultMessages(_Strict):
    """``message_on_fault`` (spec §4.10.3): MB4 codes posted on the fault's rising edge."""

    following_error: int = Field(default=0, ge=0, le=255)
    monitoring: int = Field(default=0, ge=0, le=255)
    emergency_stop: int = Field(default=0, ge=0, le=255)


class PlcStartRule(_Strict):
    """``start_program_on_input`` (spec §4.10.3): MB2 := program, M0.2 := 1 on an input edge."""

    input: str = Field(description="input bit, e.g. E0.2")
    program: int = Field(ge=0, le=99)
    edge: Literal["rising", "falling"] = "rising"


class PlcCopyRule(_Strict):
    """A bit follows another bit every cycle: ``{from: E0.4, to: A0.5, invert: false}``."""

    model_config = ConfigDict(extra="forbid", populate_by_name=True)

    source: str = Field(alias="from", description="E/A/M bit read from the process image")
    to: str = Field(description="A or M bit written")
    invert: bool = False


class PlcOptions(_Strict):
    """The scripted PLC stand-in for the undocumented Step5 program (spec §4.10.2, §4.10.3)."""

    cycle_ms: float | None = Field(
        default=None, gt=0, description="PLC cycle; None: variant's plc_ms_per_1000 x instructions/1000"
    )
    instructions: int = Field(default=230, ge=1, description="program length for the derived cycle time")
    loaded: bool | None = Field(
        default=None, description="a PLC program is in FLASH at power-on; None: iff rules/hook are configured"
    )
    flash_bytes: int = Field(default=32768, ge=1, description="PLC program memory (longer download: T3;4 I.0)")
    auto_ack_m_functions_ms: float | None = Field(default=None, ge=0)
    limit_switches: list[PlcLimitRule] = Field(default_factory=list)
    message_on_fault: PlcFaultMessages | None = None
    start_program_on_input: list[PlcStartRule] = Field(default_factory=list)
    copy_bits: list[PlcCopyRule] = Field(default_factory=list)
    hook: str | None = Field(
        default=None,
        description="'package.module:function' called every cycle: Python code, so the file must be trusted",
    )

    @field_validator("hook")
    @classmethod
    def _hook_loads(cls, value: str | None) -> str | None:
        """The hook is imported when the file is loaded: a bad one is one line with its place."""
        if value is not None:
            from devsim.devices.gms96.plc import load_hook

            load_hook(value)
        return value


#: Keys only a SERS configuration has.
_SERS_KEYS = frozenset({"address", "autostart", "baud", "input_level", "service_switch", "current_class",
                        "supply_class", "options", "supply_voltage", "heatsink_temperature", "initially_selected",
                        "broadcast_reply", "encoding"})


class Gms96Config(_Strict):
    """What a user can set for one GMS96 card (``--config FILE.yaml`` or a plant file)."""

    dil: DilSwitch = Field(default_factory=DilSwitch)
    variant: str = Field(default="KSA15-2R", description="K1 | KSA15 | KSA15-2 | KS4 | KS8 | ... (+R)")
    params: dict[int, int] = Field(default_factory=dict, description="factory N parameters {index: value}")
    axis: AxisGeometry = Field(default_factory=AxisGeometry)
    link: LinkOptions = Field(default_factory=LinkOptions)
    plc: PlcOptions = Field(default_factory=PlcOptions)
    boot_time: float = Field(default=0.5, ge=0, description="seconds of silence after power-on/reset")
    flash_erase_s: float = Field(default=3.0, ge=0, le=5.0, description="silence after p1;100 / p3;100")
    eeprom_write_s: float = Field(default=0.1, ge=0, description="BUSY time of s85;170")
    queue_capacity: int = Field(default=64, ge=1)
    max_programs: int = Field(default=100, ge=1, le=100)
    max_total_commands: int = Field(default=8192, ge=1)
    out_of_range: Literal["clamp", "ignore"] = "clamp"
    override_pot_pct: float = Field(default=100.0, ge=0, le=125)
    tool_offset: int = Field(default=0, description="tool offset T (no command sets it, spec §5.9)")
    h22_data_address: int | None = Field(
        default=None, ge=0, le=240, description="H22;0 copies the measurement to this data byte (FB 254/22)"
    )

    @model_validator(mode="before")
    @classmethod
    def _not_a_sers_file(cls, value: object) -> object:
        """A SERS configuration given to a GMS96 says so, instead of 'unknown field'."""
        if isinstance(value, dict):
            sers_keys = sorted(set(map(str, value)) & _SERS_KEYS)
            if sers_keys:
                raise ValueError(
                    f"this looks like a SERS configuration ({', '.join(sers_keys)}), not a GMS96 one:"
                    " a GMS96 has dil, variant, params (N parameters), axis, link, plc ..."
                )
        return value

    @field_validator("params", mode="before")
    @classmethod
    def _params(cls, value: object) -> object:
        """Accept ``{N10: 300}`` as well as ``{10: 300}``; each N parameter must exist (§2.3.1 N)."""
        if isinstance(value, dict):
            out = {}
            for key, val in value.items():
                text = str(key).strip().upper()
                number = text[1:] if text.startswith("N") else text
                if not (number.isascii() and number.isdigit()) or int(number) not in N_PARAMETERS:
                    raise ValueError(f"{key}: no such parameter")
                out[int(number)] = val
            return out
        return value

    @field_validator("params")
    @classmethod
    def _param_ranges(cls, value: dict[int, int]) -> dict[int, int]:
        """Each value within the parameter's own range, as the manual states it."""
        for index, number in value.items():
            pdef = N_PARAMETERS[index]
            low = INT24_MIN if pdef.minimum is None else pdef.minimum
            high = INT24_MAX if pdef.maximum is None else pdef.maximum
            if not low <= number <= high:
                raise ValueError(f"N{index}: {number} is outside {low} … {high}")
        return value
