"""Configuration of one simulated POSELESTA II/III (spec poselesta.md §1.1, §3.2, §3.5, §3.6,
§4.8, §4.9 and the choices of §7.2): the variant, the axis resolutions that place the decimal
point of the word formats, the read-in and output options and the initial machine parameters."""

from __future__ import annotations

from string import hexdigits
from typing import Annotated, Any, Literal

from devsim.core.points import ascii_digits, strip_blanks
from devsim.core.settings import Check, Keys, Meta, Settings, doc, field
from devsim.devices.poselesta.parameters import check_parameter

__all__ = ["PoselestaConfig"]

_AXES = ("X", "Y", "Z", "D")
_NonNegative = Annotated[float, Meta(ge=0)]
_PrintedLine = Annotated[str, Meta(min_length=1, max_length=20, pattern="^[ -~]+$")]  # 7-bit printable ASCII


def _axis(key: Any) -> str:
    if key not in _AXES:
        raise ValueError(f"Input should be {', '.join(map(repr, _AXES[:-1]))} or {_AXES[-1]!r}")
    return str(key)


def _decimal_count(_axis: str, decimals: int) -> int:
    if not 0 <= decimals <= 6:
        raise ValueError("decimals must be 0 … 6")
    return decimals


def _decimals(value: dict[str, int]) -> dict[str, int]:
    return {**dict.fromkeys(_AXES, 3), **value}


def _parameter_number(key: Any) -> int:
    if isinstance(key, int) and not isinstance(key, bool):
        return key
    text = strip_blanks(str(key))  # (str.strip also took NBSP, U+3000, FS … US: '\u30003' was P3)
    if not ascii_digits(text):
        raise ValueError("Input should be a valid integer, unable to parse string as an integer")
    return int(text)


def _key_code(key: Any) -> int:
    """A key code as a number (0x48, 72) or hex text ("48", "0x48") in ASCII hex digits (int(text, 16)
    also read the Arabic-Indic '٤٨', '+48', '4_8' and NBSP or FS around them); one of the 45 codes of
    §3.10."""
    from devsim.devices.poselesta.codes import KEY_CODES

    if isinstance(key, int):
        code = key
    else:
        text = strip_blanks(str(key))
        digits = text[2:] if text[:2] in ("0x", "0X") else text
        if not (digits and digits.isascii() and all(c in hexdigits for c in digits)):
            raise ValueError(f"{text!r} is no key code in hex digits (48 or 0x48)")
        code = int(digits, 16)
    if code not in KEY_CODES:
        raise ValueError(f"{code:02X} is not a key code of the keyboard (spec §3.10)")
    return code


def _param(number: int, setting: float) -> float:
    check_parameter(number, setting)
    return setting


class Plc(Settings):
    """The PLC side of the MST acknowledge V22/7, played by a plant helper (spec §4.4.3)."""

    mst_ack: Annotated[Literal["bridged", "delayed", "manual"], doc(
        "bridged: acknowledge = the strobes; delayed: H rise_ms after a strobe rises, L fall_ms after it falls; "
        "manual: input.mst_ack is set by hand")] = "bridged"
    rise_ms: Annotated[float, Meta(ge=0), doc("delayed: acknowledge H this long after a strobe rises")] = 35.0
    fall_ms: Annotated[float, Meta(ge=0), doc("delayed: acknowledge L this long after a strobe falls")] = 15.0
    tool_change_ms: Annotated[_NonNegative | None, doc(
        "M06 is acknowledged (a 50 ms pulse on V22/5) this long after it is output; null: by hand")] = None
    m10_release_ms: Annotated[_NonNegative | None, doc(
        "a non-self-holding M10 gets its 50 ms negative pulse on V22/6 this long after it is output")] = None


class Axis(Settings):
    """One axis: its reference marks and homing (spec §5.6)."""

    reference_marks: Annotated[list[float], doc(
        "positions of the encoder's reference marks, mm from the power-on position")] = field(
        default_factory=lambda: [-10.0])
    home_direction: Annotated[Literal[-1, 1], doc("the way homing searches")] = -1
    reference_value: Annotated[float, doc("the actual value at the accepted mark, mm")] = 0.0


class Axes(Settings):
    """The four axes X, Y, Z, D."""

    x: Axis = field(default_factory=Axis)
    y: Axis = field(default_factory=Axis)
    z: Axis = field(default_factory=Axis)
    d: Axis = field(default_factory=Axis)


#: The nested parts ``plc``, ``axes.<a>`` and ``axes``.
PLC, AXIS, AXES = Plc, Axis, Axes


class PoselestaConfig(Settings):
    """What a user can set for one POSELESTA (--config FILE.yaml or a plant file)."""

    variant: Annotated[Literal["II", "III"], doc("POS II or POS III (§1.1 of the spec)")] = "III"
    decimals: Annotated[dict[Any, int], Keys(_axis, "X | Y | Z | D", entry=_decimal_count), Check(_decimals), doc(
        "decimals of each axis's resolution (3 = 0.001 mm); the word format is 7 digits")] = field(
        default_factory=lambda: dict.fromkeys(_AXES, 3))
    eob: Annotated[Literal["CRLF", "CR"], doc("end of block on output (spec G-EOB)")] = "CRLF"
    leader_nul: Annotated[int, Meta(ge=0, le=1000), doc("NUL bytes before an output (G-LEADER)")] = 0
    trailer_nul: Annotated[int, Meta(ge=0, le=1000), doc("NUL bytes after an output")] = 0
    parity_error: Annotated[Literal["abort", "skip"], doc(
        "ISO byte with wrong parity after %: WERTBEREICHES-UEBERLAUF or dropped")] = "abort"
    ascii_bit7: Annotated[Literal["ignore", "abort"], doc(
        "ASCII code: a byte with bit 7 set is masked (an ISO character, even parity; odd parity aborts: §2.6) or "
        "always aborts the read-in")] = "ignore"
    strict_block_numbers: Annotated[bool, doc("a block without N aborts the read-in")] = False
    honour_xoff: Annotated[bool, doc(
        "DC3 (XOFF) from the host pauses an output, DC1 (XON) resumes it; not the control's behaviour, which has "
        "no flow control (spec G-FLOW, §3.6)")] = False
    rx_timeout_s: Annotated[Annotated[float, Meta(gt=0)] | None, doc(
        "a read-in that hears nothing this long after its start or its last byte fails (spec G-TIMEOUT; the "
        "control has no timeout: null)")] = None
    printer_block_separator: Annotated[_PrintedLine | None, doc(
        "a line the printer (T1) prints after every block, e.g. '#' (spec G-PRN-HASH); null: none, '#' is only "
        "a skipped block's mark")] = None
    max_blocks_total: Annotated[int, Meta(ge=1), doc("program memory, blocks over all programs")] = 2000
    params: Annotated[dict[Any, float], Keys(_parameter_number, "parameter number", entry=_param), doc(
        "initial machine parameters, e.g. {70: 3, 71: 0} (P1 … P98)")] = {}
    boot_time: Annotated[float, Meta(ge=0), doc("seconds after power-on until NC ready (§2.4.5: about 2 s)")] = 2.0
    input_rise_ms: Annotated[float, Meta(ge=0, le=1000), doc(
        "§2.3: an input V19–V22 going L→H reaches the control after 2.5 … 15 ms (voltage-dependent) plus ~25 ms "
        "filtering; 35 ms is the middle of that range plus the filter")] = 35.0
    input_fall_ms: Annotated[float, Meta(ge=0, le=1000), doc(
        "§2.3: an input V19–V22 going H→L reaches the control after 15 … 50 ms computing time; 32.5 ms is the "
        "middle")] = 32.5
    accel: Annotated[float, Meta(gt=0), doc("acceleration = braking ramp of every axis, mm/s² (spec §5.3)")] = 500.0
    kv_per_step: Annotated[float, Meta(gt=0), doc("Kv [1/s] per step of the gain P30–P33 (spec §5.2)")] = 1.667
    drive_speed_factor: Annotated[float, Meta(gt=0), doc(
        "drive speed at 10 V set-point = this × rapid (spec §5.2)")] = 1.2
    m06_requires_nc_start: Annotated[bool, doc("after the M06 acknowledge wait for NC-Start (spec G-M06)")] = False
    encoder_khz: Annotated[float, Meta(gt=0), doc(
        "highest encoder input frequency (4-channel adapter 100 kHz, 2-channel 8 kHz): faster is an event")] = 100.0
    count_loss_increments: Annotated[float, Meta(gt=0), doc(
        "increments an encoder drops with the fault count_loss_<axis>")] = 10.0
    g25_full_circle: Annotated[bool, doc("a G25 block runs a full circle around I/J (spec §4.12.1)")] = False
    invert_optional_stop: Annotated[bool, doc(
        "M01 stops while V21/10 is L, not H (the diagnostic table's 'M 01 aufheben'; spec G-M01)")] = False
    g13_count_is_total: Annotated[bool, doc(
        "a in G13 L a.bbb counts the passes in all, not the jumps back (spec G-LOOP)")] = False
    ijk_incremental: Annotated[bool, doc(
        "the circle centre I/J/K is relative to the arc's start point, not absolute (spec G-IJK)")] = False
    v6_peer: Annotated[Literal["host", "cassette"], doc(
        "what V6's cassette transfers T2/T3 reach: the host on the pty, or a simulated cassette recorder")] = "host"
    plc: Plc = field(default_factory=Plc)
    axes: Axes = field(default_factory=Axes)
    v8_keymap: Annotated[dict[Any, str], Keys(_key_code, "key code"), doc(
        "names of the keyboard's key codes for panel.key (spec §3.10: the legends are lost; 48 = P)")] = field(
        default_factory=lambda: {0x48: "P"})
