"""Configuration of one simulated POSELESTA II/III (spec poselesta.md §1.1, §3.2, §3.5, §3.6,
§4.8, §4.9 and the choices of §7.2): the variant, the axis resolutions that place the decimal
point of the word formats, the read-in and output options and the initial machine parameters."""

from __future__ import annotations

from typing import Any

from devsim.core.settings import Bool, DictOf, Float, Int, OneOf, Section, Setting
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


def _params(value: dict[int, float]) -> dict[int, float]:
    for number, setting in value.items():
        check_parameter(number, setting)
    return value


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
))
