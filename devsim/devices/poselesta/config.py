"""Configuration of one simulated POSELESTA II/III (spec poselesta.md §1.1, §3.2, §3.5, §3.6,
§4.8, §4.9 and the choices of §7.2): the variant, the axis resolutions that place the decimal
point of the word formats, the read-in and output options and the initial machine parameters."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator

from devsim.devices.poselesta.parameters import check_parameter

__all__ = ["PoselestaConfig"]


class PoselestaConfig(BaseModel):
    """What a user can set for one POSELESTA (``--config FILE.yaml`` or a plant file)."""

    model_config = ConfigDict(extra="forbid")

    variant: Literal["II", "III"] = Field(default="III", description="POS II or POS III (§1.1 of the spec)")
    decimals: dict[Literal["X", "Y", "Z", "D"], int] = Field(
        default_factory=lambda: {"X": 3, "Y": 3, "Z": 3, "D": 3},
        description="decimals of each axis's resolution (3 = 0.001 mm); the word format is 7 digits",
    )
    eob: Literal["CRLF", "CR"] = Field(default="CRLF", description="end of block on output (spec G-EOB)")
    leader_nul: int = Field(default=0, ge=0, le=1000, description="NUL bytes before an output (G-LEADER)")
    trailer_nul: int = Field(default=0, ge=0, le=1000, description="NUL bytes after an output")
    parity_error: Literal["abort", "skip"] = Field(
        default="abort", description="ISO byte with wrong parity after %: WERTBEREICHES-UEBERLAUF or dropped"
    )
    ascii_bit7: Literal["ignore", "abort"] = Field(
        default="ignore", description="ASCII code: a byte with bit 7 set is masked or aborts the read-in"
    )
    strict_block_numbers: bool = Field(default=False, description="a block without N aborts the read-in")
    max_blocks_total: int = Field(default=2000, ge=1, description="program memory, blocks over all programs")
    params: dict[int, float] = Field(
        default_factory=dict, description="initial machine parameters, e.g. {70: 3, 71: 0} (P1 … P98)"
    )
    boot_time: float = Field(default=2.0, ge=0, description="seconds after power-on until NC ready (§2.4.5: about 2 s)")

    @field_validator("decimals")
    @classmethod
    def _decimals(cls, value: dict[str, int]) -> dict[str, int]:
        for axis, decimals in value.items():
            if not 0 <= decimals <= 6:
                raise ValueError(f"{axis}: decimals must be 0 … 6")
        return {**{"X": 3, "Y": 3, "Z": 3, "D": 3}, **value}

    @field_validator("params")
    @classmethod
    def _params(cls, value: dict[int, float]) -> dict[int, float]:
        for number, setting in value.items():
            check_parameter(number, setting)
        return value
