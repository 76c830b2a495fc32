"""Configuration of one simulated GMS96 card (spec gms96.md §2.2, Appendix A).

DIL switch (manual §2.2): address 0..31 (switches 1..4 inverted + switch 5 = +16), switch 6
interpolation, switch 7 protocol S/E, switch 8 baud 9600/38400.  The switch is read only at
power-on or after a reset (emergency-stop release).  Axis geometry is in increments from the
power-on position: reference cam, index marks, mechanical end stops and optional position
ranges wired to inputs (the GMS has no limit-switch inputs of its own, spec §5.11).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Annotated, Any, Literal

from devsim.core.points import ascii_digits, ascii_upper, strip_blanks
from devsim.core.settings import Check, Keys, Meta, Settings, doc, field
from devsim.devices.gms96.nparams import N_TABLE, n_range

__all__ = [
    "AxisGeometry", "DilSwitch", "Gms96Config", "LimitSwitch", "LinkOptions", "PlcCopyRule",
    "PlcFaultMessages", "PlcLimitRule", "PlcOptions", "PlcStartRule",
]

_Byte = Annotated[int, Meta(ge=0, le=255)]
_Pair = tuple[float, float]


class DilSwitch(Settings):
    """The 8-position DIL switch (manual §2.2), as its meaning rather than switch positions."""

    address: Annotated[int, Meta(ge=0, le=31), doc("switches 1..4 (+16 with switch 5)")] = 3
    interpolation: Annotated[bool, doc("switch 6: behind a GMS-I card")] = False
    protocol: Annotated[Literal["S", "E"], doc("switch 7: DIN 19244 S- or E-version")] = "S"
    baud: Annotated[Literal[9600, 38400], doc("switch 8")] = 9600


class LimitSwitch(Settings):
    """A position range that drives an input bit (spec §5.11 a)."""

    input: Annotated[str, doc("input bit, e.g. E0.3")]
    low: Annotated[float | None, doc("active from here (None: -inf)")] = None
    high: Annotated[float | None, doc("active up to here (None: +inf)")] = None


class AxisGeometry(Settings):
    """Where things sit on the axis, in increments from the power-on position (spec §5.6)."""

    cam: Annotated[_Pair | None, doc("reference cam [low, high] or null (no cam)")] = (-20000.0, -15000.0)
    cam_input: Literal["E2.1", "E2.0"] = "E2.1"
    cam_polarity: Annotated[Literal["NO", "NC"], doc("NO: 24 V while on the cam")] = "NO"
    index_period: Annotated[int, Meta(gt=0), doc("increments between index marks (counts/rev)")] = 4096
    index_offset: float = 0.0
    counter_marks: Annotated[list[float], doc("reference marks of the counter input's scale (Q with P2.5)")] = []
    end_stops: Annotated[_Pair | None, doc("mechanical end stops [low, high]")] = None
    limit_switches: list[LimitSwitch] = []
    kv_per_n10: Annotated[float, Meta(gt=0), doc("Kv [1/s] per unit of N10 (spec §5.7)")] = 0.2
    position_after_reset: Literal["zero", "keep"] = "zero"
    brake_stop_ms: Annotated[float, Meta(ge=0)] = 50.0
    i2t_t_allow_s: Annotated[float, Meta(gt=0)] = 2.0


class LinkOptions(Settings):
    """Link-layer choices the manual leaves open (spec §3.7, §3.9, Appendix A)."""

    response_delay: Annotated[float, Meta(ge=0, le=0.1), doc("seconds before a reply")] = 0.0
    char_timeout: Annotated[float, Meta(gt=0), doc("inter-character timeout (s)")] = 0.05
    unknown_command_reply: Literal["ack", "none"] = "ack"
    unknown_short_command_reply: Literal["ack", "none"] = "ack"
    on_queue_full: Literal["defer", "drop", "nack"] = "defer"
    e_version_features: list[Literal["fcb", "acd", "dfc"]] = field(default_factory=lambda: ["fcb", "acd", "dfc"])
    # (spec §2.3 [R]: the manual has no broadcast; IEC 60870-5-2's for a one-octet address field is
    # 255, all ones.  Any integer passed before: 0..31 is a card's own address, >255 no octet at all.)
    broadcast_address: Annotated[Literal[255] | None, doc(
        "255, IEC 60870-5-2's broadcast address; None = no broadcast")] = None
    error_line_idle: Annotated[bool, doc(
        "FT1.2 rule R4: after a detected frame error accept a new frame only after >= 33 bit times of line idle "
        "(False: resynchronise at once)")] = True


class PlcLimitRule(Settings):
    """Limit-switch rule (spec §4.10.3, §5.11): an input → STOP (M0.0) or abort (M0.1).

    ``stop``: M0.0 follows the switch (set while active, released when it clears, so the
    interrupted move continues).  ``abort``: M0.1 is pulsed on the active edge, and again every
    cycle while the switch is active and the axis is commanded towards ``direction``, so the
    axis can always be driven back out of the switch."""

    input: Annotated[str, doc("input bit, e.g. E0.3")]
    action: Literal["stop", "abort"] = "abort"
    message: Annotated[_Byte, doc("code into MB4 on the active edge (0 = none)")] = 0
    active_low: Annotated[bool, doc("normally-closed switch: active at 0 V")] = False
    direction: Annotated[Literal["+", "-", "any"], doc("only act on motion this way")] = "any"


class PlcFaultMessages(Settings):
    """MB4 codes posted on the fault's rising edge (spec §4.10.3)."""

    following_error: _Byte = 0
    monitoring: _Byte = 0
    emergency_stop: _Byte = 0


class PlcStartRule(Settings):
    """MB2 := program, M0.2 := 1 on an input edge (spec §4.10.3)."""

    input: Annotated[str, doc("input bit, e.g. E0.2")]
    program: Annotated[int, Meta(ge=0, le=99)]
    edge: Literal["rising", "falling"] = "rising"


class PlcCopyRule(Settings, rename={"source": "from"}):
    """A bit follows another bit every cycle: {from: E0.4, to: A0.5, invert: false}."""

    source: Annotated[str, doc("E/A/M bit read from the process image")]
    to: Annotated[str, doc("A or M bit written")]
    invert: bool = False


def _hook_loads(value: str | None) -> str | None:
    """The hook is imported when the file is loaded: a bad one is one line with its place."""
    if value is not None:
        from devsim.devices.gms96.plc import load_hook

        load_hook(value)
    return value


class PlcOptions(Settings):
    """The scripted PLC stand-in for the undocumented Step5 program (spec §4.10.2, §4.10.3)."""

    cycle_ms: Annotated[Annotated[float, Meta(gt=0)] | None, doc(
        "PLC cycle; None: variant's plc_ms_per_1000 x instructions/1000")] = None
    instructions: Annotated[int, Meta(ge=1), doc("program length for the derived cycle time")] = 230
    loaded: Annotated[bool | None, doc(
        "a PLC program is in FLASH at power-on; None: iff rules/hook are configured")] = None
    flash_bytes: Annotated[int, Meta(ge=1), doc("PLC program memory (longer download: T3;4 I.0)")] = 32768
    auto_ack_m_functions_ms: Annotated[float, Meta(ge=0)] | None = None
    limit_switches: list[PlcLimitRule] = []
    message_on_fault: PlcFaultMessages | None = None
    start_program_on_input: list[PlcStartRule] = []
    copy_bits: list[PlcCopyRule] = []
    hook: Annotated[str | None, Check(_hook_loads), doc(
        "'package.module:function' called every cycle: Python code, so the file must be trusted")] = None


#: Keys only a SERS configuration has.
_SERS_KEYS = frozenset({"address", "autostart", "baud", "input_level", "service_switch", "current_class",
                        "supply_class", "options", "supply_voltage", "heatsink_temperature", "initially_selected",
                        "broadcast_reply", "encoding", "ack_each_terminator", "error_trailing_star", "ok_after_error",
                        "counter_decrement_first", "i6_mode", "list_decimals", "query_units", "query_fixed_decimals",
                        "query_name_style", "spontaneous_fault_messages"})


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
    text = ascii_upper(strip_blanks(str(key)))  # (str.strip also took NBSP, U+3000, FS … US)
    number = text[1:] if text.startswith("N") else text
    if not ascii_digits(number) or int(number) not in N_TABLE:
        raise ValueError("no such parameter")
    return int(number)


def _param_range(index: int, number: int) -> int:
    """A value within the parameter's own range, as the manual states it."""
    low, high = n_range(N_TABLE[index])
    if not low <= number <= high:
        raise ValueError(f"{number} is outside {low} … {high}")
    return number


def _variant(name: str) -> str:
    """A variant Appendix A lists (``KSA15-2R``, ``G96-KS8``, any case); before, an unknown one
    passed the file's checks and failed the card's creation with ``KeyError: 'ABC'``."""
    from devsim.devices.gms96.variants import VARIANTS, variant

    try:
        variant(name)
    except KeyError:
        raise ValueError(f"no such variant {name!r} (variants: {', '.join(VARIANTS)})") from None
    return name


class Gms96Config(Settings):
    """What a user can set for one GMS96 card (--config FILE.yaml or a plant file)."""

    dil: DilSwitch = field(default_factory=DilSwitch)
    variant: Annotated[str, Check(_variant), doc("K1 | KSA15 | KSA15-2 | KS4 | KS8 | ... (+R)")] = "KSA15-2R"
    params: Annotated[dict[Any, int], Keys(_n_parameter, "N parameter", entry=_param_range), doc(
        "factory N parameters {index: value}")] = {}
    axis: AxisGeometry = field(default_factory=AxisGeometry)
    link: LinkOptions = field(default_factory=LinkOptions)
    plc: PlcOptions = field(default_factory=PlcOptions)
    boot_time: Annotated[float, Meta(ge=0), doc("seconds of silence after power-on/reset")] = 0.5
    flash_erase_s: Annotated[float, Meta(ge=0, le=5.0), doc("silence after p1;100 / p3;100")] = 3.0
    eeprom_write_s: Annotated[float, Meta(ge=0), doc("BUSY time of s85;170")] = 0.1
    queue_capacity: Annotated[int, Meta(ge=1)] = 64
    max_programs: Annotated[int, Meta(ge=1, le=100)] = 100
    max_total_commands: Annotated[int, Meta(ge=1)] = 8192
    out_of_range: Literal["clamp", "ignore"] = "clamp"
    override_pot_pct: Annotated[float, Meta(ge=0, le=125)] = 100.0
    tool_offset: Annotated[int, doc("tool offset T (no command sets it, spec §5.9)")] = 0
    h22_data_address: Annotated[Annotated[int, Meta(ge=0, le=240)] | None, doc(
        "H22;0 copies the measurement to this data byte (FB 254/22)")] = None

    @classmethod
    def screen(cls, data: Mapping[Any, Any]) -> None:
        _not_a_sers_file(data)
