"""Configuration of one simulated GMS96 card (spec gms96.md §2.2, Appendix A).

DIL switch (manual §2.2): address 0..31 (switches 1..4 inverted + switch 5 = +16), switch 6
interpolation, switch 7 protocol S/E, switch 8 baud 9600/38400.  The switch is read only at
power-on or after a reset (emergency-stop release).  Axis geometry is in increments from the
power-on position: reference cam, index marks, mechanical end stops and optional position
ranges wired to inputs (the GMS has no limit-switch inputs of its own, spec §5.11).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from devsim.core.settings import (
    Bool,
    DictOf,
    Float,
    Int,
    ListOf,
    Maybe,
    OneOf,
    PairOf,
    Section,
    Setting,
    Text,
)
from devsim.devices.gms96.tables import INT24_MAX, INT24_MIN, N_PARAMETERS

__all__ = [
    "AXIS_GEOMETRY", "DilSwitch", "Gms96Config", "LIMIT_SWITCH", "LINK_OPTIONS", "PLC_COPY_RULE",
    "PLC_FAULT_MESSAGES", "PLC_LIMIT_RULE", "PLC_OPTIONS", "PLC_START_RULE",
]

_BYTE = Int(ge=0, le=255)

#: The 8-position DIL switch (manual §2.2), as its meaning rather than switch positions.
DilSwitch = Section("The 8-position DIL switch (manual §2.2), as its meaning rather than switch positions.", (
    Setting("address", Int(ge=0, le=31), 3, "switches 1..4 (+16 with switch 5)"),
    Setting("interpolation", Bool(), False, "switch 6: behind a GMS-I card"),
    Setting("protocol", OneOf("S", "E"), "S", "switch 7: DIN 19244 S- or E-version"),
    Setting("baud", OneOf(9600, 38400), 9600, "switch 8"),
))

#: A position range that drives an input bit (spec §5.11 a); the PLC decides what it means.
LIMIT_SWITCH = Section("A position range that drives an input bit (spec §5.11 a).", (
    Setting("input", Text(), doc="input bit, e.g. E0.3"),
    Setting("low", Maybe(Float()), None, "active from here (None: -inf)"),
    Setting("high", Maybe(Float()), None, "active up to here (None: +inf)"),
))

#: Where things sit on the axis, in increments from the power-on position (spec §5.6).
AXIS_GEOMETRY = Section("Where things sit on the axis, in increments from the power-on position (spec §5.6).", (
    Setting("cam", Maybe(PairOf(Float())), (-20000.0, -15000.0), "reference cam [low, high] or null (no cam)"),
    Setting("cam_input", OneOf("E2.1", "E2.0"), "E2.1"),
    Setting("cam_polarity", OneOf("NO", "NC"), "NO", "NO: 24 V while on the cam"),
    Setting("index_period", Int(gt=0), 4096, "increments between index marks (counts/rev)"),
    Setting("index_offset", Float(), 0.0),
    Setting("counter_marks", ListOf(Float()), [], "reference marks of the counter input's scale (Q with P2.5)"),
    Setting("end_stops", Maybe(PairOf(Float())), None, "mechanical end stops [low, high]"),
    Setting("limit_switches", ListOf(LIMIT_SWITCH), []),
    Setting("kv_per_n10", Float(gt=0), 0.2, "Kv [1/s] per unit of N10 (spec §5.7)"),
    Setting("position_after_reset", OneOf("zero", "keep"), "zero"),
    Setting("brake_stop_ms", Float(ge=0), 50.0),
    Setting("i2t_t_allow_s", Float(gt=0), 2.0),
))

#: Link-layer choices the manual leaves open (spec §3.7, §3.9, Appendix A).
LINK_OPTIONS = Section("Link-layer choices the manual leaves open (spec §3.7, §3.9, Appendix A).", (
    Setting("response_delay", Float(ge=0, le=0.1), 0.0, "seconds before a reply"),
    Setting("char_timeout", Float(gt=0), 0.05, "inter-character timeout (s)"),
    Setting("unknown_command_reply", OneOf("ack", "none"), "ack"),
    Setting("unknown_short_command_reply", OneOf("ack", "none"), "ack"),
    Setting("on_queue_full", OneOf("defer", "drop", "nack"), "defer"),
    Setting("e_version_features", ListOf(OneOf("fcb", "acd", "dfc")), ["fcb", "acd", "dfc"]),
    Setting("broadcast_address", Maybe(Int()), None, "e.g. 255; None = no broadcast"),
    Setting("error_line_idle", Bool(), True,
            "FT1.2 rule R4: after a detected frame error accept a new frame only after >= 33 bit "
            "times of line idle (False: resynchronise at once)"),
))

#: Limit-switch rule (spec §4.10.3, §5.11): an input → STOP (M0.0) or abort (M0.1) + message.
#: ``stop``: M0.0 follows the switch (set while active, released when it clears, so the
#: interrupted move continues).  ``abort``: M0.1 is pulsed on the active edge, and again every
#: cycle while the switch is active and the axis is commanded towards ``direction``, so the
#: axis can always be driven back out of the switch.
PLC_LIMIT_RULE = Section("Limit-switch rule (spec §4.10.3, §5.11): an input → STOP (M0.0) or abort (M0.1).", (
    Setting("input", Text(), doc="input bit, e.g. E0.3"),
    Setting("action", OneOf("stop", "abort"), "abort"),
    Setting("message", _BYTE, 0, "code into MB4 on the active edge (0 = none)"),
    Setting("active_low", Bool(), False, "normally-closed switch: active at 0 V"),
    Setting("direction", OneOf("+", "-", "any"), "any", "only act on motion this way"),
))

#: ``message_on_fault`` (spec §4.10.3): MB4 codes posted on the fault's rising edge.
PLC_FAULT_MESSAGES = Section("MB4 codes posted on the fault's rising edge (spec §4.10.3).", (
    Setting("following_error", _BYTE, 0),
    Setting("monitoring", _BYTE, 0),
    Setting("emergency_stop", _BYTE, 0),
))

#: ``start_program_on_input`` (spec §4.10.3): MB2 := program, M0.2 := 1 on an input edge.
PLC_START_RULE = Section("MB2 := program, M0.2 := 1 on an input edge (spec §4.10.3).", (
    Setting("input", Text(), doc="input bit, e.g. E0.2"),
    Setting("program", Int(ge=0, le=99)),
    Setting("edge", OneOf("rising", "falling"), "rising"),
))

#: A bit follows another bit every cycle: ``{from: E0.4, to: A0.5, invert: false}``.
PLC_COPY_RULE = Section("A bit follows another bit every cycle: {from: E0.4, to: A0.5, invert: false}.", (
    Setting("source", Text(), doc="E/A/M bit read from the process image", alias="from"),
    Setting("to", Text(), doc="A or M bit written"),
    Setting("invert", Bool(), False),
))


def _hook_loads(value: str | None) -> str | None:
    """The hook is imported when the file is loaded: a bad one is one line with its place."""
    if value is not None:
        from devsim.devices.gms96.plc import load_hook

        load_hook(value)
    return value


#: The scripted PLC stand-in for the undocumented Step5 program (spec §4.10.2, §4.10.3).
PLC_OPTIONS = Section("The scripted PLC stand-in for the undocumented Step5 program (spec §4.10.2, §4.10.3).", (
    Setting("cycle_ms", Maybe(Float(gt=0)), None,
            "PLC cycle; None: variant's plc_ms_per_1000 x instructions/1000"),
    Setting("instructions", Int(ge=1), 230, "program length for the derived cycle time"),
    Setting("loaded", Maybe(Bool()), None, "a PLC program is in FLASH at power-on; None: iff rules/hook are configured"),
    Setting("flash_bytes", Int(ge=1), 32768, "PLC program memory (longer download: T3;4 I.0)"),
    Setting("auto_ack_m_functions_ms", Maybe(Float(ge=0)), None),
    Setting("limit_switches", ListOf(PLC_LIMIT_RULE), []),
    Setting("message_on_fault", Maybe(PLC_FAULT_MESSAGES), None),
    Setting("start_program_on_input", ListOf(PLC_START_RULE), []),
    Setting("copy_bits", ListOf(PLC_COPY_RULE), []),
    Setting("hook", Maybe(Text()), None,
            "'package.module:function' called every cycle: Python code, so the file must be trusted",
            check=_hook_loads),
))


#: Keys only a SERS configuration has.
_SERS_KEYS = frozenset({"address", "autostart", "baud", "input_level", "service_switch", "current_class",
                        "supply_class", "options", "supply_voltage", "heatsink_temperature", "initially_selected",
                        "broadcast_reply", "encoding"})


def _not_a_sers_file(value: Mapping[Any, Any]) -> None:
    """A SERS configuration given to a GMS96 says so, instead of 'unknown field'."""
    sers_keys = sorted(set(map(str, value)) & _SERS_KEYS)
    if sers_keys:
        raise ValueError(
            f"this looks like a SERS configuration ({', '.join(sers_keys)}), not a GMS96 one:"
            " a GMS96 has dil, variant, params (N parameters), axis, link, plc ..."
        )


def _n_parameter(key: Any) -> int:
    """``N10`` or ``10``: each N parameter must exist (§2.3.1 N)."""
    text = str(key).strip().upper()
    number = text[1:] if text.startswith("N") else text
    if not (number.isascii() and number.isdigit()) or int(number) not in N_PARAMETERS:
        raise ValueError("no such parameter")
    return int(number)


def _param_ranges(value: dict[int, int]) -> dict[int, int]:
    """Each value within the parameter's own range, as the manual states it."""
    for index, number in value.items():
        pdef = N_PARAMETERS[index]
        low = INT24_MIN if pdef.minimum is None else pdef.minimum
        high = INT24_MAX if pdef.maximum is None else pdef.maximum
        if not low <= number <= high:
            raise ValueError(f"N{index}: {number} is outside {low} … {high}")
    return value


#: What a user can set for one GMS96 card (``--config FILE.yaml`` or a plant file).
Gms96Config = Section("What a user can set for one GMS96 card (--config FILE.yaml or a plant file).", (
    Setting("dil", DilSwitch, {}),
    Setting("variant", Text(), "KSA15-2R", "K1 | KSA15 | KSA15-2 | KS4 | KS8 | ... (+R)"),
    Setting("params", DictOf(_n_parameter, Int(), "N parameter"), {}, "factory N parameters {index: value}",
            check=_param_ranges),
    Setting("axis", AXIS_GEOMETRY, {}),
    Setting("link", LINK_OPTIONS, {}),
    Setting("plc", PLC_OPTIONS, {}),
    Setting("boot_time", Float(ge=0), 0.5, "seconds of silence after power-on/reset"),
    Setting("flash_erase_s", Float(ge=0, le=5.0), 3.0, "silence after p1;100 / p3;100"),
    Setting("eeprom_write_s", Float(ge=0), 0.1, "BUSY time of s85;170"),
    Setting("queue_capacity", Int(ge=1), 64),
    Setting("max_programs", Int(ge=1, le=100), 100),
    Setting("max_total_commands", Int(ge=1), 8192),
    Setting("out_of_range", OneOf("clamp", "ignore"), "clamp"),
    Setting("override_pot_pct", Float(ge=0, le=125), 100.0),
    Setting("tool_offset", Int(), 0, "tool offset T (no command sets it, spec §5.9)"),
    Setting("h22_data_address", Maybe(Int(ge=0, le=240)), None,
            "H22;0 copies the measurement to this data byte (FB 254/22)"),
), before=_not_a_sers_file)
