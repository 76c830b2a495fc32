"""Configuration of one simulated POSELESTA II/III (spec poselesta.md §1.1, §3.2, §3.5, §3.6,
§4.8, §4.9 and the choices of §7.2): the variant, the axis resolutions that place the decimal
point of the word formats, the read-in and output options and the initial machine parameters."""

from __future__ import annotations

from typing import Any

from devsim.core.settings import Bool, DictOf, Float, Int, ListOf, Maybe, OneOf, Section, Setting, Text
from devsim.devices.poselesta.parameters import check_parameter

__all__ = ["PoselestaConfig"]

_AXES = ("X", "Y", "Z", "D")


def _axis(key: Any) -> str:
    if key not in _AXES:
        raise ValueError(f"Input should be {', '.join(map(repr, _AXES[:-1]))} or {_AXES[-1]!r}")
    return str(key)


def _decimals(value: dict[str, int]) -> dict[str, int]:
    for axis, decimals in value.items():
        if not 0 <= decimals <= 6:
            raise ValueError(f"{axis}: decimals must be 0 … 6")
    return {**dict.fromkeys(_AXES, 3), **value}


def _parameter_number(key: Any) -> int:
    try:
        return int(str(key).strip())
    except ValueError:
        raise ValueError("Input should be a valid integer, unable to parse string as an integer") from None


def _key_code(key: Any) -> int:
    """A key code as a number (0x48, 72) or hex text ("48"); one of the 45 codes of §3.10."""
    from devsim.devices.poselesta.codes import KEY_CODES

    code = key if isinstance(key, int) else int(str(key), 16)
    if code not in KEY_CODES:
        raise ValueError(f"{code:02X} is not a key code of the keyboard (spec §3.10)")
    return code


def _params(value: dict[int, float]) -> dict[int, float]:
    for number, setting in value.items():
        check_parameter(number, setting)
    return value


#: The PLC side of the MST acknowledge V22/7 (spec §4.4.3, §8 S15/S16): a plant helper.
PLC = Section("The PLC side of the MST acknowledge V22/7, played by a plant helper (spec §4.4.3).", (
    Setting("mst_ack", OneOf("bridged", "delayed", "manual"), "bridged",
            "bridged: acknowledge = the strobes; delayed: H rise_ms after a strobe rises, L fall_ms after "
            "it falls; manual: input.mst_ack is set by hand"),
    Setting("rise_ms", Float(ge=0), 35.0, "delayed: acknowledge H this long after a strobe rises"),
    Setting("fall_ms", Float(ge=0), 15.0, "delayed: acknowledge L this long after a strobe falls"),
    Setting("tool_change_ms", Maybe(Float(ge=0)), None,
            "M06 is acknowledged (a 50 ms pulse on V22/5) this long after it is output; null: by hand"),
    Setting("m10_release_ms", Maybe(Float(ge=0)), None,
            "a non-self-holding M10 gets its 50 ms negative pulse on V22/6 this long after it is output"),
))

#: One axis: where its reference marks are and how it homes (spec §5.6, G-HOME).
AXIS = Section("One axis: its reference marks and homing (spec §5.6).", (
    Setting("reference_marks", ListOf(Float()), [-10.0],
            "positions of the encoder's reference marks, mm from the power-on position"),
    Setting("home_direction", OneOf(-1, 1), -1, "the way homing searches"),
    Setting("reference_value", Float(), 0.0, "the actual value at the accepted mark, mm"),
))
AXES = Section("The four axes X, Y, Z, D.", tuple(Setting(a, AXIS, {}) for a in "xyzd"))

#: What a user can set for one POSELESTA (``--config FILE.yaml`` or a plant file).
PoselestaConfig = Section("What a user can set for one POSELESTA (--config FILE.yaml or a plant file).", (
    Setting("variant", OneOf("II", "III"), "III", "POS II or POS III (§1.1 of the spec)"),
    Setting("decimals", DictOf(_axis, Int(), "X | Y | Z | D"), dict.fromkeys(_AXES, 3),
            "decimals of each axis's resolution (3 = 0.001 mm); the word format is 7 digits", check=_decimals),
    Setting("eob", OneOf("CRLF", "CR"), "CRLF", "end of block on output (spec G-EOB)"),
    Setting("leader_nul", Int(ge=0, le=1000), 0, "NUL bytes before an output (G-LEADER)"),
    Setting("trailer_nul", Int(ge=0, le=1000), 0, "NUL bytes after an output"),
    Setting("parity_error", OneOf("abort", "skip"), "abort",
            "ISO byte with wrong parity after %: WERTBEREICHES-UEBERLAUF or dropped"),
    Setting("ascii_bit7", OneOf("ignore", "abort"), "ignore",
            "ASCII code: a byte with bit 7 set is masked or aborts the read-in"),
    Setting("strict_block_numbers", Bool(), False, "a block without N aborts the read-in"),
    Setting("max_blocks_total", Int(ge=1), 2000, "program memory, blocks over all programs"),
    Setting("params", DictOf(_parameter_number, Float(), "parameter number"), {},
            "initial machine parameters, e.g. {70: 3, 71: 0} (P1 … P98)", check=_params),
    Setting("boot_time", Float(ge=0), 2.0, "seconds after power-on until NC ready (§2.4.5: about 2 s)"),
    Setting("accel", Float(gt=0), 500.0, "acceleration = braking ramp of every axis, mm/s² (spec §5.3)"),
    Setting("kv_per_step", Float(gt=0), 1.667, "Kv [1/s] per step of the gain P30–P33 (spec §5.2)"),
    Setting("drive_speed_factor", Float(gt=0), 1.2, "drive speed at 10 V set-point = this × rapid (spec §5.2)"),
    Setting("m06_requires_nc_start", Bool(), False, "after the M06 acknowledge wait for NC-Start (spec G-M06)"),
    Setting("encoder_khz", Float(gt=0), 100.0,
            "highest encoder input frequency (4-channel adapter 100 kHz, 2-channel 8 kHz): faster is an event"),
    Setting("count_loss_increments", Float(gt=0), 10.0, "increments an encoder drops with the fault count_loss_<axis>"),
    Setting("g25_full_circle", Bool(), False, "a G25 block runs a full circle around I/J (spec §4.12.1)"),
    Setting("v6_peer", OneOf("host", "cassette"), "host",
            "what V6's cassette transfers T2/T3 reach: the host on the pty, or a simulated cassette recorder"),
    Setting("plc", PLC, {}),
    Setting("axes", AXES, {}),
    Setting("v8_keymap", DictOf(_key_code, Text(), "key code"), {0x48: "P"},
            "names of the keyboard's key codes for panel.key (spec §3.10: the legends are lost; 48 = P)"),
))
