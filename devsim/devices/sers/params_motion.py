"""SERS parameter rows: operating parameters (manual §4.8.4)."""

from __future__ import annotations

from devsim.devices.sers.paramdef import POS_MAX as _POS_MAX
from devsim.devices.sers.paramdef import POS_MIN as _POS_MIN
from devsim.devices.sers.paramdef import RW_E as _RW_E
from devsim.devices.sers.paramdef import Rows

__all__ = ["ROWS"]

_p = Rows()

# ============================================================================================
# 4.8.4 Operating parameters
# ============================================================================================
_p(
    1014,
    "Positioniermodus",
    "positioning mode",
    choices=frozenset({0, 1, 2, 3}),
    invalid_errno=80,
    **_RW_E,
    doc="0 RELATIV; 1 RELATIV LÖSCHEN (P51:=0 before start); 2 ABSOLUT; 3 relative with overflow "
    "counter C1 (X = C1*P103 + P51).",
    attr="positioning_mode",
)
_W_DOC = (
    "Range at gear 1:1, P123=1: rotational ±214748.3647°, translational ±167772.1599 mm, "
    "incremental ±2147483639 inc."
)
_p(
    47,
    "Lage-Sollwert",
    "position setpoint",
    aliases=("W",),
    kind="position",
    minimum=_POS_MIN,
    maximum=_POS_MAX,
    saved_with_p1117=True,
    doc="Path (relative modes) or target (absolute). Start with E. " + _W_DOC,
    attr="position_setpoint",
)
_p(
    1051,
    "Neue Relativposition",
    "new relative position",
    aliases=("WR",),
    kind="position",
    minimum=_POS_MIN,
    maximum=_POS_MAX,
    default=None,
    readable=False,
    doc="As W and sets P1014=0. (Manual heading: 'Neue Relativposition (Lage-Sollwert relativ)'.)",
)
_p(
    1052,
    "Neue Absolutposition",
    "new absolute position",
    aliases=("WA",),
    kind="position",
    minimum=_POS_MIN,
    maximum=_POS_MAX,
    default=None,
    readable=False,
    doc="As W and sets P1014=2. (Manual heading: 'Neue Absolutposition (Lage-Sollwert absolut)'.)",
)
for _n, _name, _en, _alias, _doc in (
    (1111, "Lage-Sollwert Polynom", "position setpoint polynomial", "WP", "as W, polynomial segment"),
    (
        1112,
        "Lage-Sollwert relativ Polynom",
        "relative position setpoint polynomial",
        "WRP",
        "as WR, polynomial segment",
    ),
    (
        1113,
        "Lage-Sollwert absolut Polynom",
        "absolute position setpoint polynomial",
        "WAP",
        "as WA, polynomial segment",
    ),
    (
        1114,
        "Lage-Sollwert Polynom Ende",
        "position setpoint polynomial end",
        "WPT",
        "as W, last polynomial segment",
    ),
    (
        1115,
        "Lage-Sollwert relativ Polynom Ende",
        "relative position setpoint polynomial end",
        "WRPT",
        "as WR, last polynomial segment",
    ),
    (
        1116,
        "Lage-Sollwert absolut Polynom Ende",
        "absolute position setpoint polynomial end",
        "WAPT",
        "as WA, last polynomial segment",
    ),
):
    _p(
        _n,
        _name,
        _en,
        aliases=(_alias,),
        kind="position",
        minimum=_POS_MIN,
        maximum=_POS_MAX,
        default=None,
        readable=False,
        doc=_doc.capitalize() + " (§4.6.7).",
    )
_p(
    51,
    "Lage-Istwert",
    "actual position",
    kind="position",
    minimum=_POS_MIN,
    maximum=_POS_MAX,
    doc="Actual position; may be assigned. 0 after power-on unless stored with POSSAVE (P1004=4).",
)
_p(
    103,
    "Modulwert für Lage-Sollwert",
    "modulo value for position setpoint",
    kind="position",
    minimum=0,
    min_exclusive=True,
    maximum=_POS_MAX,
    default=360,
    too_large_errno=92,
    **_RW_E,
    doc="Modulo for endless operation (modes 0/1; overflow base in mode 3). Must be an exact number "
    "of increments and larger than the largest single relative move.",
    attr="modulo",
)
_p(
    1043,
    "Phasenposition löschen / Motor Nachfahren",
    "clear phase position / motor follow-up",
    minimum=0,
    maximum=3,
    readable=False,
    commands=("POS0", "POSR"),
    doc="1 = POS0 (move to electrical phase zero, then P51:=0); 2 = POSR (move to P47 at P41 after "
    "step error P11/P12=32); 3 = POSR without error. Also ends polynomial mode.",
)
_p(
    1138,
    "POSR Versuche",
    "POSR attempts",
    minimum=0,
    maximum=65536,
    **_RW_E,
    doc="n = up to n automatic POSR attempts after a step-angle error (manual range 0..65536).",
    attr="posr_attempts",
)
_p(
    1139,
    "POSR Wartezeit",
    "POSR waiting time",
    kind="fixed",
    decimals=1,
    minimum=0,
    maximum=327.6,
    default=1.0,
    **_RW_E,
    doc="Wait before automatic correction; 1.0 = 0.1 s.",
    attr="posr_wait",
)
_p(
    1140,
    "POSR Modus",
    "POSR mode",
    minimum=0,
    maximum=3,
    **_RW_E,
    doc="Bit 0: correct also at standstill; bit 1: P1138 attempts renewed after each success.",
    attr="posr_mode",
)
_p(
    1001,
    "Nullphase verlassen",
    "leave zero phase",
    minimum=0,
    maximum=3,
    **_RW_E,
    doc="1/2/3 = keep 0.1°/0.2°/0.3° away from multiples of 1.8°.",
    attr="leave_zero_phase",
)
_p(
    1039,
    "Nachlaufweg",
    "overrun distance",
    kind="position",
    minimum=_POS_MIN,
    maximum=_POS_MAX,
    **_RW_E,
    doc="Overrun after the event of a ':' statement (0 = off).",
    attr="overrun",
)
_p(
    1058,
    "Position Speichern bei Unterspannung",
    "save position on undervoltage",
    minimum=0,
    maximum=1,
    **_RW_E,
    doc="1 = POSSAVE when the supply falls below U_B.",
    attr="save_position_on_undervoltage",
)
_p(
    91,
    "Geschwindigkeit - Positionieren",
    "velocity - positioning",
    aliases=("V",),
    kind="velocity",
    minimum=0,
    min_exclusive=True,
    maximum=10000,
    default=100,
    too_large_errno=122,
    too_small_errno=121,
    **_RW_E,
    doc="Positioning velocity; max 10000 at rotational weighting (U/min).",
    attr="velocity",
)
_p(
    1019,
    "Geschwindigkeit Handfahren langsam",
    "velocity jog slow",
    kind="velocity",
    default=30,
    **_RW_E,
    doc="Jog slow speed (x P108).",
    attr="jog_velocity_slow",
)
_p(
    1020,
    "Geschwindigkeit Handfahren schnell",
    "velocity jog fast",
    kind="velocity",
    default=300,
    **_RW_E,
    doc="Jog fast speed (x P108).",
    attr="jog_velocity_fast",
)
_p(
    41,
    "Geschwindigkeit Referenzfahren",
    "velocity homing",
    kind="velocity",
    default=60,
    **_RW_E,
    doc="Homing speed while the reference input is not set (x P108); also POSR speed.",
    attr="homing_velocity",
)
_p(
    1003,
    "Geschwindigkeit Referenzfahren langsam",
    "velocity homing slow",
    kind="velocity",
    default=10,
    **_RW_E,
    doc="Homing speed after the reference input is set; backlash speed.",
    attr="homing_velocity_slow",
)
_p(
    108,
    "Feedrate override",
    "feedrate override",
    minimum=0,
    maximum=100,
    default=100,
    **_RW_E,
    doc="Percent; multiplies P41, P1019, P1020.",
    attr="feedrate_override",
)
_p(
    138,
    "Beschleunigung - Positionieren",
    "acceleration - positioning",
    aliases=("A",),
    kind="acceleration",
    minimum=2,
    maximum=100000,
    default=100,
    too_large_errno=120,
    too_small_errno=119,
    **_RW_E,
    doc="Positioning acceleration and deceleration; max 100000 rad/s² (rotational).",
    attr="acceleration",
)
_p(
    1018,
    "Beschleunigung - Handfahren",
    "acceleration - jog",
    kind="acceleration",
    default=100,
    **_RW_E,
    doc="Jog acceleration (also used to stop a ':' statement).",
    attr="jog_acceleration",
)
_p(
    42,
    "Beschleunigung - Referenzfahren",
    "acceleration - homing",
    kind="acceleration",
    default=100,
    **_RW_E,
    doc="Homing acceleration.",
    attr="homing_acceleration",
)
_p(
    1030,
    "Beschleunigung bei Antriebsfehler",
    "acceleration on drive error",
    kind="acceleration",
    default=1000,
    **_RW_E,
    doc="Deceleration on a drive error.",
    attr="error_deceleration",
)
_p(
    1032,
    "Rampenform der Beschleunigung",
    "ramp shape",
    minimum=0,
    maximum=1,
    **_RW_E,
    doc="0 = exponential; 1 = sinusoidal.",
    attr="ramp_shape",
)
_p(
    1005,
    "Beschleunigung Abschnitt 1",
    "acceleration section 1",
    minimum=0,
    maximum=100,
    default=100,
    **_RW_E,
    doc="% of A.",
    attr="ramp_acceleration1",
)
_p(
    1007,
    "Geschwindigkeit Abschnitt 1",
    "velocity section 1",
    minimum=0,
    maximum=100,
    default=100,
    **_RW_E,
    doc="% of V.",
    attr="ramp_velocity1",
)
_p(
    1006,
    "Beschleunigung Abschnitt 2",
    "acceleration section 2",
    minimum=0,
    maximum=100,
    default=100,
    **_RW_E,
    doc="% of A.",
    attr="ramp_acceleration2",
)
_p(
    1008,
    "Geschwindigkeit Abschnitt 2",
    "velocity section 2",
    minimum=0,
    maximum=100,
    default=100,
    **_RW_E,
    doc="% of V.",
    attr="ramp_velocity2",
)
_p(
    1096,
    "Abrampen/Abbremsen Polynomende",
    "braking ramp polynomial end",
    aliases=("B",),
    kind="acceleration",
    maximum=100000,
    default=100,
    **_RW_E,
    doc="Braking ramp of the last polynomial segment; max 100000 rad/s² (rotational).",
    attr="polynomial_deceleration",
)
_p(
    147,
    "Referenzfahr Parameter",
    "homing parameters",
    minimum=0,
    maximum=511,
    **_RW_E,
    doc="Bits: 1 direction negative; 2 limit switch as reference; 4 move to electrical reset "
    "position; 8 respect software limits; 16 reference input inverted; 32 switch centre; "
    "64 zero pulse; 128 switch + zero pulse + reset position; 256 SERVO load-angle reference.",
    attr="homing_parameters",
)
_WEIGHT_CODES = frozenset({0, 64, 2, 66, 1, 17})
_p(
    76,
    "Wichtungsart für Lagedaten",
    "position data weighting",
    choices=_WEIGHT_CODES,
    default=2,
    **_RW_E,
    doc="0/64 inkr (motor/load), 2/66 ° (motor/load), 1 mm, 17 in.",
    attr="position_weighting",
)
_p(
    44,
    "Wichtungsart Geschwindigkeitsdaten",
    "velocity data weighting",
    choices=_WEIGHT_CODES,
    default=2,
    **_RW_E,
    doc="0/64/2/66 U/min, 1 mm/min, 17 in/min.",
    attr="velocity_weighting",
)
_p(
    160,
    "Wichtungsart Beschleunigungsdaten",
    "acceleration data weighting",
    choices=_WEIGHT_CODES,
    default=2,
    **_RW_E,
    doc="0/64/2/66 rad/s², 1 mm/s², 17 in/s².",
    attr="acceleration_weighting",
)
_p(
    123,
    "Vorschubkonstante",
    "feed constant",
    kind="fixed",
    decimals=4,
    minimum=0,
    min_exclusive=True,
    default=1,
    length_unit=True,
    **_RW_E,
    doc="Distance per spindle revolution (lead 5 mm -> 5), in the position length unit (mm/in). "
    "The manual says the unit depends on 'P44 (Wichtungsart Lagedaten)' -- P76 meant.",
    attr="feed_constant",
)
_p(
    121,
    "Lastgetriebe-Eingangsumdrehung",
    "gear input revolutions",
    minimum=1,
    default=1,
    **_RW_E,
    doc="Gear input revolutions (motor side); ratio g = P121/P122 (8:1 -> P121=8, P122=1).",
    attr="gear_input",
)
_p(
    122,
    "Lastgetriebe-Ausgangsumdrehung",
    "gear output revolutions",
    minimum=1,
    default=1,
    **_RW_E,
    doc="Gear output revolutions (load side).",
    attr="gear_output",
)
_p(
    1037,
    "Backlash",
    "backlash",
    kind="position",
    minimum=0,
    maximum=_POS_MAX,
    **_RW_E,
    doc="Backlash distance (0 = off); direction from P147 bit 0.",
    attr="backlash",
)


ROWS = tuple(_p)
