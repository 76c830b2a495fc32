"""GMS96 variants: current ratings, feedback, I/O counts and the stepper versions (spec §4.12.4,
manual §6)."""

from __future__ import annotations

import msgspec

from devsim.core.points import ascii_upper

__all__ = ["DEFAULT_VARIANT", "VARIANTS", "Variant", "variant"]

# ---------------------------------------------------------------------------------------------
# Variants (spec §4.12.4, manual §6)
# ---------------------------------------------------------------------------------------------


class Variant(msgspec.Struct, frozen=True):
    """Hardware data of one card type (manual §6 "Leistungsdaten"; currents are DC peak values).

    ``continuous_current_a`` = "Nennstrom", ``supply_v`` = rated DC-bus voltage ("Nenn-Spannung").
    ``feedback``: "resolver" | "encoder" | "none" (stepper).  ``io_inputs``/``io_outputs`` as in
    the data table; ``input_bits``/``output_bits`` = fitted process-image bits from E0.0/A0.0
    (K1: E0.0..E0.5 / A0.0..A0.5; others E0.0..E2.1 / A0.0..A1.2, spec §4.11.1).  Power data of
    the GD96 controller card (no power stage) are ``None``.
    """

    name: str
    peak_current_a: float | None
    continuous_current_a: float | None
    supply_v: int | None
    feedback: str
    stepper: bool
    undervoltage_v: int | None = None
    overvoltage_v: int | None = None
    ballast_on_v: int | None = None
    dc_link_capacitor_uf: int | None = None
    braking_current_a: float | None = None
    height: str = ""
    io_inputs: int = 17
    io_outputs: int = 11
    input_bits: int = 18
    output_bits: int = 11
    analog_output: bool = True
    plc_ms_per_1000: int | None = None
    increments_per_rev: int = 4096
    max_step_frequency_hz: int | None = None
    logic_from_dc_bus: bool = True
    power_stage: bool = True
    doc: str = ""


def _ksa(name: str, resolver: bool, **kw: object) -> Variant:
    return Variant(name=name, feedback="resolver" if resolver else "encoder", stepper=False, **kw)  # type: ignore[arg-type]


_K1 = dict(
    peak_current_a=15.0,
    continuous_current_a=5.0,
    supply_v=70,
    undervoltage_v=30,
    overvoltage_v=95,
    ballast_on_v=85,
    dc_link_capacitor_uf=1000,
    braking_current_a=15.0,
    height="48 mm",
    io_inputs=7,
    io_outputs=6,
    input_bits=6,
    output_bits=6,
    analog_output=False,
    plc_ms_per_1000=87,
)
_KSA15 = dict(
    peak_current_a=15.0,
    continuous_current_a=5.0,
    supply_v=70,
    undervoltage_v=30,
    overvoltage_v=95,
    ballast_on_v=80,
    dc_link_capacitor_uf=1000,
    braking_current_a=15.0,
    height="68 mm",
    plc_ms_per_1000=87,
)
_KSA15_2 = dict(
    peak_current_a=15.0,
    continuous_current_a=5.0,
    supply_v=160,
    undervoltage_v=60,
    overvoltage_v=190,
    ballast_on_v=180,
    dc_link_capacitor_uf=100,
    braking_current_a=15.0,
    height="68 mm",
    plc_ms_per_1000=87,
)
_KSA20 = dict(
    peak_current_a=19.0,
    continuous_current_a=9.0,
    supply_v=250,
    undervoltage_v=100,
    overvoltage_v=340,
    ballast_on_v=320,
    dc_link_capacitor_uf=380,
    braking_current_a=20.0,
    height="112 mm",
    plc_ms_per_1000=87,
)
_KSA65 = dict(
    peak_current_a=65.0,
    continuous_current_a=18.0,
    supply_v=250,
    undervoltage_v=100,
    overvoltage_v=340,
    ballast_on_v=320,
    dc_link_capacitor_uf=380,
    braking_current_a=65.0,
    height="135 mm",
    plc_ms_per_1000=87,
)
_KD = dict(
    supply_v=310,
    undervoltage_v=200,
    overvoltage_v=400,
    ballast_on_v=380,
    dc_link_capacitor_uf=200,
    braking_current_a=10.0,
    height="112 mm",
    plc_ms_per_1000=88,
    logic_from_dc_bus=False,
)
_HD = dict(
    supply_v=560,
    undervoltage_v=250,
    overvoltage_v=680,
    ballast_on_v=650,
    dc_link_capacitor_uf=330,
    plc_ms_per_1000=88,
    logic_from_dc_bus=False,
)
_KS = dict(
    supply_v=160,
    undervoltage_v=60,
    overvoltage_v=190,
    ballast_on_v=180,
    dc_link_capacitor_uf=100,
    plc_ms_per_1000=72,
    increments_per_rev=6400,
    max_step_frequency_hz=500_000,
)

_VARIANT_LIST: tuple[Variant, ...] = (
    _ksa("K1", False, doc="G96-K1; no F connector I/O unit [R: encoder feedback]", **_K1),
    _ksa("KSA15", False, doc="G96-KSA15, encoder feedback", **_KSA15),
    _ksa("KSA15R", True, doc="G96-KSA15R, resolver", **_KSA15),
    _ksa("KSA15-2", False, doc="G96-KSA15-2, encoder feedback", **_KSA15_2),
    _ksa("KSA15-2R", True, doc="G96-KSA15-2R, resolver (manual's own example name)", **_KSA15_2),
    Variant(
        name="KS4",
        feedback="none",
        stepper=True,
        peak_current_a=4.0,
        continuous_current_a=2.0,
        braking_current_a=5.0,
        height="68 mm",
        doc="G96-KS4 3-phase stepper: 6400 steps/rev (50-pole motor), max 500 kHz; analog out [R]",
        **_KS,
    ),
    Variant(
        name="KS8",
        feedback="none",
        stepper=True,
        peak_current_a=8.0,
        continuous_current_a=4.0,
        braking_current_a=15.0,
        height="80 mm",
        doc="G96-KS8 3-phase stepper: 6400 steps/rev (50-pole motor), max 500 kHz; analog out [R]",
        **_KS,
    ),
    _ksa("KSA20", False, doc="G96-KSA20, encoder feedback", **_KSA20),
    _ksa("KSA20R", True, doc="G96-KSA20R, resolver", **_KSA20),
    _ksa("KSA65", False, doc="G96-KSA65, encoder feedback", **_KSA65),
    _ksa("KSA65R", True, doc="G96-KSA65R, resolver", **_KSA65),
    _ksa("KD8", True, peak_current_a=8.0, continuous_current_a=5.0, doc="KD8, resolver only", **_KD),
    _ksa("KD12", True, peak_current_a=12.0, continuous_current_a=5.0, doc="KD12, resolver only", **_KD),
    _ksa(
        "HD15",
        True,
        peak_current_a=15.0,
        continuous_current_a=3.0,
        braking_current_a=5.0,
        height="6U",
        doc="HD15, resolver only",
        **_HD,
    ),
    _ksa(
        "HD50",
        True,
        peak_current_a=50.0,
        continuous_current_a=15.0,
        braking_current_a=14.0,
        height="112 mm",
        doc="HD50, resolver only",
        **_HD,
    ),
    Variant(
        name="GD96",
        feedback="encoder",
        stepper=False,
        peak_current_a=None,
        continuous_current_a=None,
        supply_v=None,
        power_stage=False,
        analog_output=True,
        doc="GD96 controller card with ±10 V analog output for an external amplifier (mentioned in "
        "N11/N45, Appendix A); not in the manual's data table, power data unknown",
    ),
)

#: Variant table keyed by the configuration name (Appendix A), without the "G96-" prefix.
VARIANTS: dict[str, Variant] = {v.name: v for v in _VARIANT_LIST}

#: Spec Appendix A default (``variant: KSA15-2R``).
DEFAULT_VARIANT = "KSA15-2R"


def variant(name: str) -> Variant:
    """Look up a variant tolerantly: "G96-KSA15-2R", "gms96-ksa15-2r", "KSA15-2R" are equal."""
    key = ascii_upper(name.strip(" "))  # (str.upper: 'kſa15' with the long s U+017F was KSA15)
    for prefix in ("GMS96-", "G96-"):
        if key.startswith(prefix):
            key = key[len(prefix) :]
    if key not in VARIANTS and key.endswith("R") and key[:-1] in VARIANTS:
        key = key[:-1]  # e.g. "KD8R": KD/HD are resolver-only anyway
    return VARIANTS[key]
