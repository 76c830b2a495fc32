"""GMS96 N parameters (machine data) as kit rows, one :class:`~devsim.core.parameters.Param` each
(spec §4.6, manual §2.3.1 N).

A row's ``name`` is the manual's (German) designation, ``doc`` its English name; ``extra`` holds
``needs_restart`` (the new value only takes effect at the next card start: saved with ``s85;170``
and the card restarted -- only N21 per the manual) and ``note`` (what the manual and the spec
say beyond the name).  ``minimum``/``maximum`` ``None``: the manual gives no range, the 24-bit
field range applies (:func:`n_range`).  Every N parameter is saved
by ``s85;170`` ("Alle Eingaben des N-Befehls" [M §2.3.1 s]).  ``attr`` names the accessor the
model reads the value by (:class:`~devsim.devices.gms96.params.NParameters`).
"""

from __future__ import annotations

from devsim.core.parameters import Param, ParameterTable

__all__ = [
    "INT24_MAX",
    "INT24_MIN",
    "N_DUAL_VALUE",
    "N_SIMULATOR_DEFAULTS",
    "N_STORED_ONLY",
    "N_TABLE",
    "n_range",
]

#: Full 24-bit two's complement range of a parameter field P1..P3 [M §2.3].
INT24_MIN, INT24_MAX = -0x800000, 0x7FFFFF

#: N parameters kept and answered but without an effect in the simulator (the generated
#: reference marks them "stored"): found by searching the card's code for each index.  The
#: controller gains and sample time act on a loop the simulator replaces by the v/Kv lag model
#: (N10); resolver, measurement and reserved entries have no effect a host could see; N32
#: (position monitoring on/off) and N52/N53 (I/O card counts) have one the simulator lacks.
N_STORED_ONLY: frozenset[int] = frozenset({11, 12, 13, 16, 25, 26, 32, 34, 35, 43, 44, 45, 52, 53, 54, 55, 56})

#: The accessor names of the N parameters the model reads (``params.position_gain``).
_ATTRS: dict[int, str] = {
    10: "position_gain",
    15: "i2t_level",
    17: "motion_disabled",
    19: "reference_type",
    20: "following_error_limit",
    21: "brake_output",
    22: "motor_inverted",
    23: "counter_weight",
    24: "ramp_type",
    27: "in_position_window",
    28: "in_position_time_ms",
    33: "drive_off_position",
    39: "peak_current_pct",
    41: "backlash",
    42: "backlash_speed",
    50: "binary_options",
    51: "enable_input",
}


def _n(
    index: int,
    name: str,
    name_en: str,
    default: int,
    minimum: int | None,
    maximum: int | None,
    unit: str = "",
    doc: str = "",
    *,
    needs_restart: bool = False,
) -> Param:
    return Param(
        index,
        name,
        f"§2.3.1 N{index}",
        name_en,
        minimum=minimum,
        maximum=maximum,
        unit=unit,
        default=default,
        saved=True,
        effect="stored" if index in N_STORED_ONLY else "simulated",
        attr=_ATTRS.get(index, ""),
        extra={"needs_restart": needs_restart, "note": doc},
    )


_ROWS: tuple[Param, ...] = (
    _n(
        8,
        "Grenzwert des Grundstellungsbereichs",
        "home-position window limit",
        0,
        INT24_MIN,
        INT24_MAX,
        "inc",
        "Two values: P3=0 -> lower limit, P3=1 -> upper limit (see N_DUAL_VALUE); T5;8;P3 reads them [R]. "
        "PLC queries the home-position criterion with FB 254, Accu1=12. Default 0 [R] (manual gives none).",
    ),
    _n(
        10,
        "Proportionalanteil des Lagereglers",
        "position controller P gain",
        200,
        1,
        3000,
        "",
        "Stepper software: corner frequency in kHz [10..500] above which the current controller is "
        "continuously damped; above twice that frequency pure open-loop control (N10_STEPPER_RANGE).",
    ),
    _n(
        11,
        "Differentialanteil des Lagereglers",
        "position controller D gain",
        200,
        50,
        255,
        "",
        "GD96: actual-value correction.",
    ),
    _n(12, "Zeitkonstante des Lagereglers", "position controller time constant T1", 0, 0, 15, "ms"),
    _n(13, "Integralanteil des Lagereglers", "position controller I gain", 0, 0, 9999, ""),
    _n(
        15,
        "I2t-Stromgrenze",
        "I2t current limit",
        84,
        0,
        255,
        "1/255 Imax",
        "%*2.55 of the maximum power-stage current: 255 = 100 %, default 84 = 33 %. 0 disables I2t [R].",
    ),
    _n(16, "Polzahl bei Resolver-Motoren", "pole count of resolver motors", 3, 2, 6, ""),
    _n(
        17,
        "Indexer-Fahrfunktion außer Kraft",
        "indexer motion function disabled",
        0,
        0,
        1,
        "",
        "1 = moves run normally in time but do not move the axis (M3.4 = 1); 0 = normal.",
    ),
    _n(
        19,
        "Referenz-Typ",
        "reference type (for Q-1)",
        0,
        INT24_MIN,
        INT24_MAX,
        "",
        "LSB = P1 of the Q command, middle byte = P2 of the Q command (decode_reference_type). "
        "Default 0 [R] (manual gives none).",
    ),
    _n(
        20,
        "max. zulässiger Schleppabstand",
        "max. permissible following error",
        1000,
        10,
        15000,
        "inc",
        "|following error| > N20 -> following-error fault (IDXOFF).",
    ),
    _n(
        21,
        "Bremsausgang",
        "brake output",
        1,
        0,
        1,
        "",
        "1 -> A0.0 = brake output; 0 -> A0.0 normal output. Takes effect only after the next restart "
        "of the card (so it must be saved with s85;170 first).",
        needs_restart=True,
    ),
    _n(
        22,
        "Motordrehrichtung",
        "motor direction",
        0,
        0,
        1,
        "",
        "0 = normal, 1 = inverted. Manual default '(-)'; 0 [R].",
    ),
    _n(
        23,
        "Auflösung des Zählengangs",
        "counter-input resolution (weighting)",
        1,
        1,
        8,
        "inc/pulse",
        "Each incoming counter increment counts as N23 set-point increments.",
    ),
    _n(24, "Art der Rampen", "ramp type", 1, 0, 1, "", "0 = linear, 1 = sin²."),
    _n(25, "Integralanteil während Fahrten", "I part during moves", 0, 0, 1, "", "0 = on, 1 = off."),
    _n(26, "Reglertastzeit", "controller sample time", 0, 0, 1, "", "0 = 1 ms, 1 = 500 µs."),
    _n(
        27,
        "Fenster für In-Position",
        "in-position window",
        0,
        -255,
        255,
        "inc",
        "0 or ±1..255. Positive -> A0.1 represents in-position (24 V = in position); negative -> window "
        "|value|, A0.1 free for general use. Not available in stepper operation.",
    ),
    _n(
        28,
        "Zeit für In-Position",
        "in-position time",
        1,
        1,
        255,
        "ms",
        "Following error must stay inside the window this long before in-position. Default 1 [R].",
    ),
    _n(
        32,
        "Lageüberwachung ein/aus",
        "position monitoring on/off",
        0,
        0,
        1,
        "",
        "For motors with a rotor-position sensor separate from the position feedback (block-commutated "
        "motors with 6-pole RLG; resolver motors with extra encoder). Default 0 [R].",
    ),
    _n(
        33,
        "Freifahr-Position nach Referenzfahrt",
        "drive-off position after reference run",
        0,
        INT24_MIN,
        INT24_MAX,
        "inc",
        "Used only by Q-1. Default 0 [R].",
    ),
    _n(
        34,
        "P-Anteil des Stromreglers",
        "current controller P gain",
        1200,
        0,
        32000,
        "",
        "Range [*..32000]: may be lowered to min. 150 % of the I part (N34 >= 1.5*N35), see "
        "current_gain_limits; static minimum 0 [R].",
    ),
    _n(
        35,
        "I-Anteil des Stromreglers",
        "current controller I gain",
        0,
        0,
        21333,
        "",
        "Range [0..*]: N35 <= N34/1.5 (current_gain_limits); static maximum 32000/1.5 = 21333 [R].",
    ),
    _n(
        39,
        "Spitzenstrom",
        "peak current",
        100,
        0,
        100,
        "%",
        "Reduction of the fixed hardware maximum current. Default 100 [R] (manual gives none).",
    ),
    _n(41, "Ausgleichsbetrag für Lose-Kompensation", "backlash compensation amount", 0, 0, 255, "inc"),
    _n(
        42,
        "Geschwindigkeit des Ausgleichs",
        "backlash compensation speed",
        10,
        1,
        255,
        "inc/ms",
        "Manual writes the range in round brackets '(1..255)'; no default given; 10 [R].",
    ),
    _n(
        43,
        "(reserviert) Parameter der Zwischenkreis-Messung",
        "(reserved) DC-bus measurement parameter",
        0,
        None,
        None,
        "",
        "KD/HD thresholds, undocumented; stored and reported only.",
    ),
    _n(
        44,
        "(reserviert) Parameter der Kühlkörpertemperatur-Messung",
        "(reserved) heat-sink temperature measurement parameter",
        0,
        None,
        None,
        "",
        "Undocumented; stored and reported only.",
    ),
    _n(
        45,
        "Feldsymmetrie",
        "field symmetry (resolver motors)",
        0,
        None,
        None,
        "°",
        "Compensates the angular offset between rotor and resolver. GD96: top speed [kHz] for the "
        "analog-output monitoring. No range/default in the manual; 0 [R].",
    ),
    _n(
        50,
        "einzelne binäre Werte",
        "binary options",
        6,
        0,
        None,
        "",
        "Sum of option values; bit 0 {+1}: actual-value source 0 = resolver/motor encoder, 1 = counter "
        "input. Bits 1, 2 (set by default) are undocumented (N50_BITS).",
    ),
    _n(
        51,
        "Freigabefunktion E0.0",
        "indexer enable input E0.0",
        0,
        0,
        1,
        "",
        "1: E0.0 = indexer enable (0 V blocks all moves); 0: no enable function. Default 0 [R].",
    ),
    _n(
        52,
        "Zahl der Ausgabekarten SPA",
        "number of SPA output cards",
        0,
        0,
        6,
        "",
        "> 0 switches the auxiliary serial interface to master mode. Not simulated.",
    ),
    _n(
        53,
        "Zahl der Eingabekarten SPE",
        "number of SPE input cards",
        0,
        0,
        6,
        "",
        "> 0 switches the auxiliary serial interface to master mode. Not simulated.",
    ),
    _n(54, "(reserviert)", "(reserved)", 0, None, None, "", "Stored and reported only."),
    _n(
        55,
        "(reserviert 1Vss-Teilung)",
        "(reserved: 1 Vpp interpolation)",
        0,
        None,
        None,
        "",
        "Stored and reported only.",
    ),
    _n(
        56,
        "(reserviert) Parameter der Motortemperatur-Messung",
        "(reserved) motor-temperature measurement parameter",
        0,
        None,
        None,
        "",
        "Stored and reported only.",
    ),
)


#: The N parameters (``N15``, ``n15`` and ``15`` name the same row): every N index of spec §4.6 /
#: manual §2.3.1 N; indices not in it are undefined (the card ignores them [R]).
N_TABLE = ParameterTable(_ROWS, prefix="N", name="N parameter")


def n_range(row: Param) -> tuple[int, int]:
    """The range of an N parameter as the manual states it; without one, the 24-bit field's [M §2.3]."""
    low = INT24_MIN if row.minimum is None else int(row.minimum)
    high = INT24_MAX if row.maximum is None else int(row.maximum)
    return low, high


#: N indices whose default is a simulator choice ([R]); the manual gives no "Grundstellung".
N_SIMULATOR_DEFAULTS: frozenset[int] = frozenset({8, 19, 22, 28, 32, 33, 39, 42, 43, 44, 45, 51, 54, 55, 56})

#: N parameters holding two values selected by P3 (0 = lower, 1 = upper): only N8.
N_DUAL_VALUE: frozenset[int] = frozenset({8})
