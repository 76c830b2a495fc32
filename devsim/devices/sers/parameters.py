"""SERS parameter table: every P number of the manual, with aliases, ranges, defaults and access.

Sources: manual §4.7 "Parameterübersicht" (seed lines 1730–1800: the list of all parameters),
§4.8 "SERS Parameter" (seed lines 1847–4020: one heading per parameter -- the heading is the
designation returned by ``P<n>??``), §4.2 "Adresse" (aliases), §2.1.4 (supply thresholds),
§4.8.6.1 (P1010 maximum per version), §4.8.6.15 (SERS-Programmer masks); transcribed in spec
§3.4, §4.5, §4.6, §4.8.1–§4.8.7 and §2.7.

Conventions
-----------
* Values are in user units.  Weighted kinds (``position``/``velocity``/``acceleration``) follow
  P76 / P44 / P160 (see :mod:`.units`); their ``minimum``/``maximum`` are given in the default
  weighting (°, U/min, rad/s²) where the manual states a range, else ``None`` -- the device
  re-checks weighted ranges after conversion (e.g. :meth:`.units.Scaling.pos_range`).
* ``fixed`` = fixed number of decimals independent of weighting: D/D2 (1), P1139 (1),
  P1054/P1144 (5), ADC (3), P123 (4, unit = position length unit), X and R0..R5 (3, spec
  G-ARITH).
* ``min_exclusive`` marks ranges of the form "> minimum" (V, P103, P123).
* ``invalid_errno`` is used when a value is not in ``choices`` (default 3 "ungültig"; P1014: 80;
  P0 / P1004: 82).  ``write_errno`` is used when a read-only parameter is written (default 105;
  P1034: 12).  Reading a write-only parameter -> errno 106.
* ``saved`` = "E" in the spec (stored by PSAVE).  W (P47) and R0..R5 are "S": stored only with
  P1117=1 (``saved_with_p1117``).  P51 is stored by POSSAVE only (:data:`POSSAVE_PARAMS`).
* ``default`` = factory/power-on value ([M] manual or [SIM] spec choice); for variant-dependent
  values it is the default variant SERS 06.85 (P1010 max 8400 mA, P1034 = 6).
* Command keywords (ON/OFF, RUN/QUIT/NEW, PSAVE/POSSAVE, LS/RS/LF/RF/H, POS0/POSR, VER) and bit
  addresses (I1..I16, J1..J5) are not simple aliases: see :data:`COMMAND_VALUES` and
  :data:`BIT_ADDRESSES`; they are listed in the ``commands`` field of their parameter but not
  in :data:`ALIASES`.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Literal

__all__ = [
    "ParamDef",
    "Kind",
    "PARAMETERS",
    "ALIASES",
    "COMMAND_VALUES",
    "BIT_ADDRESSES",
    "FACTORY_DEFAULTS",
    "SAVED",
    "SAVED_WITH_P1117",
    "POSSAVE_PARAMS",
    "WEIGHTED",
    "CURRENT_MAX_MA",
    "CURRENT_MAX_MA_NEW_SERIES",
    "CURRENT_RANGE_P1034",
    "SUPPLY_THRESHOLDS",
    "SUPPLY_NOMINAL_RANGE",
    "DEFAULT_VARIANT",
    "PARAMETER_MASKS",
    "PROGRAM_MASKS",
    "lookup",
]

Kind = Literal["int", "position", "velocity", "acceleration", "fixed"]
Number = int | float


@dataclass(frozen=True)
class ParamDef:
    number: int
    name: str  # German designation (manual heading) -- returned by P<n>??
    name_en: str  # English gloss (P265=1)
    aliases: tuple[str, ...] = ()
    kind: Kind = "int"
    decimals: int = 0  # for kind "fixed"
    minimum: Number | None = None
    maximum: Number | None = None
    choices: frozenset[int] | None = None
    default: Number | None = 0
    readable: bool = True
    writable: bool = True
    saved: bool = False
    saved_with_p1117: bool = False
    too_large_errno: int = 1
    too_small_errno: int = 2
    doc: str = ""
    # --- extensions beyond the brief -----------------------------------------------------------
    min_exclusive: bool = False  # range is "> minimum"
    invalid_errno: int = 3  # value not in choices
    write_errno: int = 105  # write to a read-only parameter
    length_unit: bool = False  # query answer carries the position length unit (P123)
    commands: tuple[str, ...] = ()  # command keywords / bit addresses acting on this parameter

    @property
    def weighted(self) -> bool:
        return self.kind in ("position", "velocity", "acceleration")


_TABLE: list[ParamDef] = []


def _p(number: int, name: str, name_en: str, **kw) -> None:
    _TABLE.append(ParamDef(number, name, name_en, **kw))


# Position range of W etc. in the default weighting (rotational, 4 decimals) -- §4.8.4.2.
_POS_MIN, _POS_MAX = -214748.3647, 214748.3647
_RW_E = {"saved": True}

# ============================================================================================
# 4.8.1 Inputs / outputs (§4.8.1)
# ============================================================================================
_p(
    1300,
    "Eingänge",
    "inputs",
    aliases=("IN",),
    minimum=0,
    maximum=255,
    writable=False,
    commands=tuple(f"I{i}" for i in range(1, 9)),
    doc="State of inputs I1..I8, binary (I1=1 ... I8=128); P1300=11 -> I1, I2, I4. "
    "IF syntax also I1..I8 and legacy IN0..IN255.",
)
_p(
    1301,
    "Eingänge I/O-Erweiterung",
    "inputs I/O extension",
    minimum=0,
    maximum=255,
    writable=False,
    commands=tuple(f"I{i}" for i in range(9, 17)),
    doc="Inputs I9..I16 (valid only with option IO).",
)
_p(
    1021,
    "DigIn-Freigabe",
    "digital input enable",
    minimum=0,
    maximum=255,
    **_RW_E,
    doc="Manual functions on the inputs when the service switch is off: 1 I1 left slow; 2 I2 right "
    "slow; 4 I3 left fast; 8 I4 right fast; 16 I5 homing; 32 I6 motor ON/OFF (ON also clears "
    "P11/P12); 64 I7 stop (manual prints 84); 128 I8 start program.",
)
_p(
    1056,
    "Endschalter und Digin",
    "limit switches and digital inputs",
    writable=False,
    doc="Internal use only.",
)
_p(
    1022,
    "DigIn-Label-Freigabe",
    "digital input label enable",
    minimum=0,
    maximum=255,
    **_RW_E,
    doc="Inputs used as address lines in parallel mode (P1022=15 -> I1..I4); P1021 must contain 128.",
)
_p(
    1098,
    "Freigabe Programmsprung",
    "program jump enable",
    minimum=0,
    maximum=255,
    **_RW_E,
    doc="Event mode: bit n-1 -> rising edge on In jumps to Ln (§4.5.2).",
)
_p(
    1023,
    "Start-Freigabe",
    "start enable",
    minimum=0,
    maximum=1,
    **_RW_E,
    doc="0 = program start on an edge at I8; 1 = start while I8 is set (level).",
)
_p(
    1046,
    "Analog-Eingang ADC",
    "analog input ADC",
    aliases=("ADC",),
    kind="fixed",
    decimals=3,
    minimum=0,
    maximum=1,
    writable=False,
    doc="Analog input, 10 bit; re-read on every use. Simulator: fraction 0.000..1.000 of 5 V (G-ADC).",
)
_p(
    1135,
    "ADC-Hysterese",
    "ADC hysteresis",
    minimum=0,
    maximum=255,
    default=7,
    **_RW_E,
    doc="x = 2^n-1 -> hysteresis n bits, resolution 10-n bits (7 = default, 7-bit resolution).",
)
_p(
    1148,
    "ADC-Offset",
    "ADC offset",
    minimum=0,
    maximum=255,
    **_RW_E,
    doc="Subtracted from the ADC value, scale 0..255 = 0..5 V.",
)
_p(
    1130,
    "Referenz-Schalter Digin Zuweisung",
    "reference switch input assignment",
    minimum=0,
    maximum=8,
    **_RW_E,
    doc="0 = standard reference input; 1..8 = input I1..I8 is the reference switch.",
)
_p(
    1038,
    "Invertieren End-/Stopschalter",
    "invert limit/stop switches",
    minimum=0,
    maximum=2,
    **_RW_E,
    doc="0 = standard (24 V = not actuated); 1 = test mode (must not be set); 2 = inverted.",
)
for _i in range(1, 17):
    _p(
        1200 + _i,
        f"Ausgang {_i}",
        f"output {_i}",
        aliases=(f"O{_i}",),
        minimum=0,
        maximum=1,
        doc=(
            f"Digital output O{_i}." if _i <= 4 else f"Extension output O{_i} (option IO only, else errno 4)."
        ),
    )
_p(
    1036,
    "Ausgang Bremse",
    "brake output",
    minimum=-4,
    maximum=4,
    **_RW_E,
    doc="On OFF: 1..4 switch O1..O4 on; -1..-4 switch O1..O4 off; 0 = off.",
)
_p(
    1024,
    "Vergleichsposition 1",
    "compare position 1",
    kind="position",
    minimum=_POS_MIN,
    maximum=_POS_MAX,
    too_large_errno=88,
    too_small_errno=89,
    **_RW_E,
    doc="When P51 = P1024 the action P1025 is executed.",
)
_p(
    1025,
    "Vergleichsausgang 1",
    "compare output 1",
    minimum=-7,
    maximum=7,
    **_RW_E,
    doc="0 off; 1..4 set O1..O4; -1..-4 clear; 5..7 set M1..M3; -5..-7 clear M1..M3. "
    "(Manual heading misprinted 'Vergleichsausgang 2', spec §7.3.)",
)
_p(
    1026,
    "Vergleichsposition 2",
    "compare position 2",
    kind="position",
    minimum=_POS_MIN,
    maximum=_POS_MAX,
    too_large_errno=90,
    too_small_errno=91,
    **_RW_E,
    doc="As P1024.",
)
_p(1027, "Vergleichsausgang 2", "compare output 2", minimum=-7, maximum=7, **_RW_E, doc="As P1025.")
_p(
    1125,
    "Ausgang Motor IN-Position",
    "output motor in position",
    minimum=-4,
    maximum=4,
    **_RW_E,
    doc="1..4: O1..O4 := P336; -1..-4 inverted.",
)
_p(
    1126,
    "Ausgang Programm läuft",
    "output program running",
    minimum=-4,
    maximum=4,
    **_RW_E,
    doc="1..4: O1..O4 := 1 while a program runs; -1..-4 inverted.",
)
_p(
    1131,
    "Ausgang SERS-Fehler",
    "output SERS error",
    minimum=-4,
    maximum=4,
    **_RW_E,
    doc="1..4: O1..O4 := 1 while P11 != 0; -1..-4 inverted.",
)
_p(
    1132,
    "Ausgang SERS-Warnung",
    "output SERS warning",
    minimum=-4,
    maximum=4,
    **_RW_E,
    doc="1..4: O1..O4 := 1 while P12 != 0; -1..-4 inverted.",
)
_p(
    1160,
    "Überlast Ausgang",
    "overload output",
    minimum=-8,
    maximum=8,
    **_RW_E,
    doc="SERVO only: 1..4 set O1..O4 latched; -1..-4 clear latched; 5..8 set O1..O4 while the "
    "overload lasts; -5..-8 clear temporarily.",
)

# ============================================================================================
# 4.8.2 System parameters
# ============================================================================================
_p(
    0,
    "E²PROM Modus",
    "EEPROM mode",
    choices=frozenset({0, 1, 2}),
    invalid_errno=82,
    commands=("QUIT", "RUN", "NEW"),
    doc="0 = not running (writing 0 ends programming mode, QUIT); 1 = run (RUN); 2 = programming "
    "mode with deletion (NEW). PGM = programming mode without deletion.",
)
_p(
    134,
    "Master-Steuerwort",
    "master control word",
    choices=frozenset({0, 7}),
    commands=("ON", "OFF"),
    doc="Motor current: ON = 7, OFF = 0.",
)
_p(
    1134,
    "Drehrichtungsumkehr",
    "direction reversal",
    minimum=0,
    maximum=1,
    **_RW_E,
    doc="1 = motor direction inverted.",
)
_p(
    1136,
    "Erhöhte Chopperfrequenz",
    "increased chopper frequency",
    minimum=0,
    maximum=1,
    **_RW_E,
    doc="12 A versions: 0 = 12 kHz, 1 = 18 kHz. Versions <= 6 A: fixed (write -> errno 105 [SIM]).",
)
_p(
    1133,
    "Firmware-Version",
    "firmware version",
    default=120901,
    writable=False,
    commands=("VER",),
    doc="Read-only; also via VER.",
)

# ============================================================================================
# 4.8.3 Status (§4.5, §4.6)
# ============================================================================================
_p(
    11,
    "Antriebsfehler",
    "drive errors",
    choices=frozenset({0}),
    doc="Error bits: 2 overtemperature, 32 step monitoring, 128 short circuit, 512 undervoltage, "
    "2048 standstill monitoring, 4096 communication, 8192 limit switch. Only 0 may be written.",
)
_p(
    12,
    "Warnungen",
    "warnings",
    choices=frozenset({0}),
    doc="Warning bits: 1 limit, 2 overtemp, 4 undervoltage, 8 internal position limit, 16 error "
    "message, 32 step monitoring, 64 setpoint limit, 128 program error, 256 arithmetic, "
    "1024 RS232 overflow, 2048 SERVO not active. Only 0 may be written.",
)
_p(
    1137,
    "Letzte Fehlermeldungsnummer (errno)",
    "last error message number (errno)",
    writable=False,
    doc="Number of the last error message (§3.6).",
)
_p(
    336,
    "Positionsstatus - In_Position",
    "position status - in position",
    aliases=("POS",),
    minimum=0,
    maximum=1,
    default=1,
    writable=False,
    doc="0 while moving, 1 when standing.",
)
_p(
    1121,
    "Selbstständige Meldung In_Position",
    "spontaneous message in position",
    minimum=0,
    maximum=1,
    **_RW_E,
    doc="1 = send '@nPOS=1' at the end of every positioning.",
)
_p(
    1129,
    "Selbstständige Meldung Fertig_Programm",
    "spontaneous message program finished",
    minimum=0,
    maximum=1,
    **_RW_E,
    doc="1 = send '@nP0=0' at the end of a program.",
)
_p(
    403,
    "Status Lageistwerte",
    "actual position status",
    default=3,
    writable=False,
    doc="3 after power-on (not homed); 0 after a successful homing run.",
)
_p(
    1015,
    "Beschleunigungsphase",
    "acceleration phase",
    minimum=0,
    maximum=1,
    writable=False,
    doc="1 while accelerating or decelerating.",
)
_p(
    1016,
    "Konstantphase",
    "constant phase",
    minimum=0,
    maximum=1,
    writable=False,
    doc="1 while moving at constant velocity.",
)
_p(
    1013,
    "Treiberstatus und Endschalter",
    "driver status and limit switches",
    minimum=0,
    maximum=65535,
    writable=False,
    commands=("J1", "J2", "J3", "J4", "J5"),
    doc="Bits: 1 limit right open (J3), 2 limit left open (J2), 4 STOP open (J4), 8 reference "
    "open (J1), 128 service switch open (J5). J values are the inverse of these bits.",
)
_p(
    1042,
    "Grenzposition überschritten",
    "limit position exceeded",
    aliases=("LP",),
    minimum=0,
    maximum=1,
    writable=False,
    doc="1 if P51 < P1040 or P51 > P1041.",
)
_p(
    1123,
    "Nächsten Polynomabschnitt laden",
    "load next polynomial segment",
    minimum=0,
    maximum=1,
    writable=False,
    doc="1 = the next polynomial segment is expected.",
)

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
)
_p(
    1140,
    "POSR Modus",
    "POSR mode",
    minimum=0,
    maximum=3,
    **_RW_E,
    doc="Bit 0: correct also at standstill; bit 1: P1138 attempts renewed after each success.",
)
_p(
    1001,
    "Nullphase verlassen",
    "leave zero phase",
    minimum=0,
    maximum=3,
    **_RW_E,
    doc="1/2/3 = keep 0.1°/0.2°/0.3° away from multiples of 1.8°.",
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
)
_p(
    1058,
    "Position Speichern bei Unterspannung",
    "save position on undervoltage",
    minimum=0,
    maximum=1,
    **_RW_E,
    doc="1 = POSSAVE when the supply falls below U_B.",
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
)
_p(
    1019,
    "Geschwindigkeit Handfahren langsam",
    "velocity jog slow",
    kind="velocity",
    default=30,
    **_RW_E,
    doc="Jog slow speed (x P108).",
)
_p(
    1020,
    "Geschwindigkeit Handfahren schnell",
    "velocity jog fast",
    kind="velocity",
    default=300,
    **_RW_E,
    doc="Jog fast speed (x P108).",
)
_p(
    41,
    "Geschwindigkeit Referenzfahren",
    "velocity homing",
    kind="velocity",
    default=60,
    **_RW_E,
    doc="Homing speed while the reference input is not set (x P108); also POSR speed.",
)
_p(
    1003,
    "Geschwindigkeit Referenzfahren langsam",
    "velocity homing slow",
    kind="velocity",
    default=10,
    **_RW_E,
    doc="Homing speed after the reference input is set; backlash speed.",
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
)
_p(
    1018,
    "Beschleunigung - Handfahren",
    "acceleration - jog",
    kind="acceleration",
    default=100,
    **_RW_E,
    doc="Jog acceleration (also used to stop a ':' statement).",
)
_p(
    42,
    "Beschleunigung - Referenzfahren",
    "acceleration - homing",
    kind="acceleration",
    default=100,
    **_RW_E,
    doc="Homing acceleration.",
)
_p(
    1030,
    "Beschleunigung bei Antriebsfehler",
    "acceleration on drive error",
    kind="acceleration",
    default=1000,
    **_RW_E,
    doc="Deceleration on a drive error.",
)
_p(
    1032,
    "Rampenform der Beschleunigung",
    "ramp shape",
    minimum=0,
    maximum=1,
    **_RW_E,
    doc="0 = exponential; 1 = sinusoidal.",
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
)
_p(
    44,
    "Wichtungsart Geschwindigkeitsdaten",
    "velocity data weighting",
    choices=_WEIGHT_CODES,
    default=2,
    **_RW_E,
    doc="0/64/2/66 U/min, 1 mm/min, 17 in/min.",
)
_p(
    160,
    "Wichtungsart Beschleunigungsdaten",
    "acceleration data weighting",
    choices=_WEIGHT_CODES,
    default=2,
    **_RW_E,
    doc="0/64/2/66 rad/s², 1 mm/s², 17 in/s².",
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
)
_p(
    121,
    "Lastgetriebe-Eingangsumdrehung",
    "gear input revolutions",
    minimum=1,
    default=1,
    **_RW_E,
    doc="Gear input revolutions (motor side); ratio g = P121/P122 (8:1 -> P121=8, P122=1).",
)
_p(
    122,
    "Lastgetriebe-Ausgangsumdrehung",
    "gear output revolutions",
    minimum=1,
    default=1,
    **_RW_E,
    doc="Gear output revolutions (load side).",
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
)

# ============================================================================================
# 4.8.5 Programming parameters
# ============================================================================================
_p(
    1100,
    "Zeitverzögerung",
    "time delay",
    aliases=("D",),
    kind="fixed",
    decimals=1,
    minimum=0.1,
    maximum=6553.5,
    readable=False,
    doc="Blocking delay in 0.1 s (D=1 -> 100 ms, D=0.1 -> 10 ms); x1.2 when P1141=0.",
)
_p(
    1141,
    "Zeitverzögerung - Korrektur",
    "time delay correction",
    minimum=0,
    maximum=1,
    **_RW_E,
    doc="0 = V01..V03 delay factor 1.2; 1 = factor 1.0.",
)
_p(
    1164,
    "Wartezeit D2",
    "waiting time D2",
    aliases=("D2",),
    kind="fixed",
    decimals=1,
    minimum=0,
    maximum=6553.5,
    doc="Non-blocking timer in 0.1 s; DB := 1 when elapsed.",
)
_p(
    1165,
    "Wartezeit Bit DB",
    "waiting time bit DB",
    aliases=("DB",),
    minimum=0,
    maximum=1,
    writable=False,
    doc="Set when D2 has elapsed.",
)
_p(
    100,
    "Zähler 1",
    "counter 1",
    aliases=("C1",),
    minimum=0,
    maximum=65535,
    doc="Unsigned 16-bit (manual: 0..65536); signed -32768..32767 overflow counter when P1014=3.",
)
_p(
    101,
    "Zähler 2",
    "counter 2",
    aliases=("C2",),
    minimum=0,
    maximum=65535,
    doc="Unsigned 16-bit counter (manual: 0..65536).",
)
_p(
    102,
    "Zähler 3",
    "counter 3",
    aliases=("C3",),
    minimum=0,
    maximum=4294967295,
    doc="Unsigned 32-bit counter.",
)
for _i in (1, 2, 3):
    _p(1100 + _i, f"Merker {_i}", f"flag {_i}", aliases=(f"M{_i}",), minimum=0, maximum=1, doc="Flag.")
_p(
    1028,
    "Listoption",
    "list option",
    minimum=0,
    maximum=31,
    default=1,
    **_RW_E,
    doc="Bits: 1 statement numbers; 2 units; 4 indented; 8 keep user line breaks; 16 LISTP texts.",
)
_p(
    1110,
    "Warten bis fertig positioniert ist",
    "wait until positioned",
    minimum=0,
    maximum=1,
    default=1,
    doc="Master: 1 = wait for own E to finish. Always 1 after power-on, not stored.",
)
_p(
    1,
    "Zieladresse",
    "target address",
    aliases=("Z",),
    minimum=0,
    maximum=127,
    doc="Master target address (0 = self); '*' (broadcast) allowed only here (errno 19 elsewhere).",
)
_p(2, "IF Senden/Erhalten", "IF send/receive", doc="Internal: master->slave IF query ('P2=336' = 'IF 336').")
_p(
    3,
    "Slave Parameterabfrage",
    "slave parameter query",
    doc="Internal buffer for master->slave reads ('#1P3=91'). Not in the §4.7 list.",
)

# ============================================================================================
# 4.8.6 Other parameters
# ============================================================================================
_p(
    1009,
    "Kommutierungstabelle",
    "commutation table",
    minimum=0,
    maximum=5,
    default=1,
    **_RW_E,
    doc="0 sine; 1 '87' characteristic; 2 characteristic 3 (sine²); 3 characteristic 4; "
    "4 half step; 5 full step.",
)
_p(
    1010,
    "Phasenstrom",
    "phase current",
    minimum=0,
    maximum=8400,
    default=4200,
    **_RW_E,
    doc="Phase current in mA; maximum per version (CURRENT_MAX_MA); default 50 % of max [SIM].",
)
_p(
    1011,
    "Stromparameter",
    "current parameters",
    minimum=0,
    maximum=63,
    default=1,
    **_RW_E,
    doc="Bits: 1 reduction at standstill; 2 boost during acceleration above P1012; 4 boost at "
    "standstill; 8 full step above P1012; 16 SERVO fixed standstill current; 32 auto ON.",
)
_p(
    1012,
    "Beschleunigung für Stromanhebung",
    "acceleration for current boost",
    kind="acceleration",
    minimum=10,
    default=10,
    **_RW_E,
    doc="Threshold for boost/full step; not below 10 rad/s².",
)
_p(
    1034,
    "Phasenstrom Bereich",
    "phase current range",
    default=6,
    writable=False,
    write_errno=12,
    saved=True,
    doc="Factory setting: 1 1A, 2 2A, 3 3A/4A, 4 4A/SERS, 5 4A, 6 6A/8A, 7 6A/SERS, 12 12A.",
)
_p(
    1159,
    "V Stromabsenkung",
    "V current reduction",
    minimum=0,
    default=10,
    **_RW_E,
    doc="Motor speed in U/min (independent of P44) for current-regulator switching.",
)
_p(
    1033,
    "Fortsetzung nach Stop",
    "continuation after stop",
    minimum=0,
    maximum=3,
    **_RW_E,
    doc="0 restart; 1 continue; 2 jump to L65; 3 as 2, further errors ignored until P1118=0.",
)
_p(
    1118,
    "Flag - L65 Fehlerbehandlung",
    "flag - L65 error handling",
    minimum=0,
    maximum=1,
    doc="1 while L65 error handling runs.",
)
_p(
    1031,
    "Handfahr-Kommando",
    "jog command",
    choices=frozenset({1, 2, 4, 8, 16}),
    default=None,
    readable=False,
    commands=("LS", "RS", "LF", "RF", "H"),
    doc="1 LS left slow; 2 RS right slow; 4 LF left fast; 8 RF right fast; 16 H homing.",
)
_p(
    1093,
    "Stop bei Handfahren",
    "stop on jog",
    minimum=0,
    maximum=1,
    **_RW_E,
    doc="Jog via input while a program runs: 0 interrupt and resume; 1 abort.",
)
_p(
    1095,
    "Handfahr-Funktionen bei Power-ON",
    "jog functions at power-on",
    minimum=0,
    maximum=1,
    **_RW_E,
    doc="0 static level activates; 1 only a rising edge.",
)
_p(
    1035,
    "Handfahren mit Timeout",
    "jog with timeout",
    minimum=0,
    maximum=1,
    default=1,
    doc="1 = serial jog stops unless repeated within 500 ms. Not stored; 1 after power-on.",
)
_p(
    1050,
    "Eigene Antriebsadresse",
    "own drive address",
    minimum=0,
    maximum=127,
    default=1,
    writable=False,
    doc="Address from DIP switch 2 (default here 1; the device sets it).",
)
_p(
    1029,
    "Schrittüberwachung Fehler/Warnung Zuweisung",
    "step monitoring error/warning assignment",
    minimum=0,
    maximum=3,
    **_RW_E,
    doc="0 none; 1 drive error P11; 2 warning P12; 3 drive error, motor stays energized.",
)
_P1053_NAME = (
    "Option Takteingang / elektrisches Getriebe / Handrad / Encodereingang / "
    "Lastwinkelüberwachung mit Nachführung / Frequenzmessung"
)
_P1053_EN = (
    "option pulse input / electronic gear / hand wheel / encoder input / "
    "load-angle monitoring with tracking / frequency measurement"
)
_p(
    1053,
    _P1053_NAME,
    _P1053_EN,
    minimum=0,
    maximum=10,
    **_RW_E,
    doc="0 off; 1 pulses I3; 2 +direction I4; 3 quadrature I3/I4; 4 load-angle I3/I4; 5..7 as 1..3 "
    "on ENC; 8 load-angle on ENC; 9 frequency on I3 (P1124); 10 frequency on ENC.",
)
_p(
    1054,
    "Wichtungsfaktor für die Eingangspulse",
    "weighting factor for input pulses",
    kind="fixed",
    decimals=5,
    minimum=-32.768,
    maximum=32.767,
    default=1,
    **_RW_E,
    doc="Unit 1/200 rev, 16 bit; outside -0.32768..0.32767 the last two decimals become 0.",
)
_p(
    1055,
    "Zeitfenster zur Messung der Frequenz",
    "time window for frequency measurement",
    minimum=1,
    default=1,
    **_RW_E,
    doc="Multiples of 2 ms.",
)
_p(1057, "Max. Lastwinkel", "max. load angle", writable=False, doc="Internal (max. load angle).")
_p(
    1002,
    "Überwachungsfenster des Lastwinkels",
    "load-angle monitoring window",
    minimum=0,
    maximum=65535,
    default=255,
    **_RW_E,
    doc="Increments (1/12800 rev, unweighted); 255 = 7.2°.",
)
_p(1124, "Frequenz bei P1053=9", "frequency at P1053=9", writable=False, doc="Pulses per P1055 window.")
_p(
    1143,
    _P1053_NAME,
    _P1053_EN + " (I3/I4)",
    minimum=0,
    maximum=5,
    **_RW_E,
    doc="0 off; 1 pulses I3; 2 +direction I4; 3 quadrature; 4 load-angle I3/I4; 5 frequency (P1146).",
)
_p(
    1144,
    "Wichtungsfaktor für die Eingangspulse",
    "weighting factor for input pulses",
    kind="fixed",
    decimals=5,
    minimum=-32.768,
    maximum=32.767,
    default=1,
    **_RW_E,
    doc="As P1054 for P1143.",
)
_p(
    1145,
    "Zeitfenster zur Messung der Frequenz",
    "time window for frequency measurement",
    minimum=1,
    default=1,
    **_RW_E,
    doc="As P1055 for P1143.",
)
_p(1146, "Frequenz bei P1143=5", "frequency at P1143=5", writable=False, doc="Pulses per P1145 window.")
_p(1147, "Takteingang Zähler 3", "pulse input counter 3", doc="Internal; do not write.")
_p(
    1094,
    "Absolutwert beibehalten bei Endschalterfehler und elektrischer Welle",
    "keep absolute value on limit error and electronic shaft",
    minimum=0,
    maximum=1,
    **_RW_E,
    doc="P1053=3/7 after a limit stop: 0 ignore blocked pulses; 1 count them.",
)
_p(1119, "Takteingang Zähler 1", "pulse input counter 1", doc="Pulse counter for P1053 modes.")
_p(1120, "Takteingang Zähler 2", "pulse input counter 2", doc="As P1119.")
_p(
    1149,
    "Softwareendschalter und Vergleichsposition bei P1053=7",
    "software limits and compare positions at P1053=7",
    minimum=0,
    maximum=1,
    **_RW_E,
    doc="0 ignored; 1 respected.",
)
_p(1152, "SERVO Modus", "SERVO mode", minimum=0, maximum=1, **_RW_E, doc="1 = SERVO mode (option E50/C).")
_p(
    1153,
    "V Lastwinkel Korrektur für SERVO-Modus",
    "V load-angle correction for SERVO mode",
    minimum=0,
    default=1000,
    **_RW_E,
    doc="U/min.",
)
_p(1154, "(undokumentiert)", "(undocumented)", writable=False, doc="Listed in §4.7 without description.")
_p(1155, "(undokumentiert)", "(undocumented)", writable=False, doc="Listed in §4.7 without description.")
_p(
    1156,
    "Ist-Beschleunigung",
    "actual acceleration",
    kind="acceleration",
    writable=False,
    doc="SERVO: measured average acceleration over the ramp.",
)
_p(1157, "(undokumentiert)", "(undocumented)", writable=False, doc="Listed in §4.7 without description.")
_p(
    1158,
    "Aktuelle Abweichung vom Sollprofil",
    "current deviation from set profile",
    kind="position",
    writable=False,
    doc="SERVO: current distance deviation from the set profile.",
)
_p(
    1161,
    "In Position Fenster",
    "in-position window",
    minimum=0,
    default=128,
    **_RW_E,
    doc="SERVO in-position window in micro-steps (12800 = 360°).",
)
_p(
    1162,
    "Aufholgeschwindigkeit verwenden im SERVO-Modus",
    "use catch-up speed in SERVO mode",
    minimum=0,
    maximum=1,
    **_RW_E,
    doc="1 = catch up lost distance with P1163.",
)
_p(
    1163,
    "Aufholgeschwindigkeit im SERVO-Modus",
    "catch-up speed in SERVO mode",
    kind="velocity",
    default=3500,
    **_RW_E,
    doc="Catch-up speed (default 3500 U/min).",
)
_p(
    1044,
    "Stillstandsüberwachung",
    "standstill monitoring",
    kind="position",
    minimum=0,
    maximum=_POS_MAX,
    **_RW_E,
    doc="Distance within which an edge on input P1045 must occur while moving; 0 = off.",
)
_p(
    1045,
    "Stillstandsüberwachung - Zuweisung Überwachungseingang",
    "standstill monitoring input",
    minimum=1,
    maximum=8,
    default=1,
    **_RW_E,
    doc="1..8 = input I1..I8.",
)
_p(
    1017,
    "Handshake Modus",
    "handshake mode",
    minimum=0,
    maximum=2,
    default=1,
    **_RW_E,
    doc="0 hardware handshake + echo; 1 no handshake + echo; 2 RS485: no echo, errors after line end.",
)
_p(
    1004,
    "E²PROM Parameter",
    "EEPROM parameters",
    choices=frozenset({2, 3, 4, 5}),
    invalid_errno=82,
    default=None,
    readable=False,
    commands=("PSAVE", "POSSAVE"),
    doc="2 PSAVE; 3 factory defaults; 4 POSSAVE (P51); 5 save R0..R5 and W.",
)
_p(
    1117,
    "Abspeichern R0 bis R5 und W",
    "save R0 to R5 and W",
    minimum=0,
    maximum=1,
    **_RW_E,
    doc="1 = PSAVE also stores R0..R5 and W.",
)
_p(
    1122,
    "Freier E²PROM Speicher",
    "free EEPROM memory",
    default=1024,
    writable=False,
    doc="Free program memory in words (x2 bytes); 1024 = empty 2 KB.",
)
_p(
    1127,
    "500µs Programm Modus",
    "500 µs program mode",
    minimum=0,
    maximum=1,
    **_RW_E,
    doc="1 = 2 ms per instruction/command (V01..V03 compatible); 0 = 500 µs.",
)
_p(265, "Sprachauswahl", "language selection", minimum=0, maximum=1, **_RW_E, doc="0 German; 1 English.")
_p(
    1040,
    "Grenzposition negativ",
    "limit position negative",
    kind="position",
    minimum=_POS_MIN,
    maximum=_POS_MAX,
    **_RW_E,
    doc="Software limit negative; P1040 > P1041 -> errno 95.",
)
_p(
    1041,
    "Grenzposition positiv",
    "limit position positive",
    kind="position",
    minimum=_POS_MIN,
    maximum=_POS_MAX,
    **_RW_E,
    doc="Software limit positive.",
)
_p(
    1047,
    "Akkumulator",
    "accumulator",
    aliases=("X",),
    kind="fixed",
    decimals=3,
    minimum=-2147483.648,
    maximum=2147483.647,
    doc="32-bit accumulator; fixed point with 3 decimals [SIM G-ARITH].",
)
for _i in range(6):
    _p(
        1080 + _i,
        f"Register {_i + 1}",
        f"register {_i + 1}",
        aliases=(f"R{_i}",),
        kind="fixed",
        decimals=3,
        minimum=-2147483.648,
        maximum=2147483.647,
        saved_with_p1117=True,
        doc="Free 32-bit signed variable (3 decimals like X [SIM]); stored by PSAVE only with P1117=1.",
    )
_p(
    1092,
    "Serviceschalter extern",
    "external service switch",
    minimum=0,
    maximum=1,
    **_RW_E,
    doc="1 = the opto input 'service switch external' enables the jog inputs.",
)
_p(
    1059,
    "Paßwort Definition",
    "password definition",
    minimum=0,
    maximum=9999,
    **_RW_E,
    doc="4-digit SERS-Programmer password; 0 = none.",
)
for _i in range(9):
    _p(
        1060 + _i,
        f"Parameter Maske [{_i}]",
        f"parameter mask [{_i}]",
        minimum=0,
        maximum=65535,
        **_RW_E,
        doc="Parameters released without password (PARAMETER_MASKS).",
    )
for _i in range(4):
    _p(
        1070 + _i,
        f"Programm Maske [{_i + 1}]",
        f"program mask [{_i + 1}]",
        minimum=0,
        maximum=65535,
        **_RW_E,
        doc=f"Labels L{16 * _i + 1}..L{16 * _i + 16} released without password.",
    )
_p(1150, "CAN interface", "CAN interface", minimum=0, maximum=1, **_RW_E, doc="1 = on (variant CAN).")
_p(
    1097,
    "Operand",
    "operand",
    minimum=-(2**31),
    maximum=2**31 - 1,
    readable=False,
    doc="CANopen: operand for the opcode in P1099; never stored.",
)
_p(
    1099,
    "Opcode",
    "opcode",
    minimum=0,
    maximum=65535,
    readable=False,
    doc="CANopen: writing executes the opcode (RUN 5 = 62213, E = 63235).",
)
_p(1142, "Profibus-ID", "Profibus ID", minimum=0, maximum=1, **_RW_E, doc="0 = old ID 0008; 1 = new ID 07B5.")

#: P number -> definition.
PARAMETERS: dict[int, ParamDef] = {}
for _d in _TABLE:
    if _d.number in PARAMETERS:  # pragma: no cover - table integrity
        raise RuntimeError(f"duplicate parameter P{_d.number}")
    PARAMETERS[_d.number] = _d
PARAMETERS = dict(sorted(PARAMETERS.items()))

#: Upper-case alias -> P number (simple aliases only; see module docstring).
ALIASES: dict[str, int] = {alias: d.number for d in PARAMETERS.values() for alias in d.aliases}

#: Command keyword -> (P number, value written).  §4.2, §4.8.2.1, §4.8.2.2, §4.8.4.2, §4.8.6.3,
#: §4.8.6.10.  (PGM = programming mode without deletion and VER = read P1133 are not writes.)
COMMAND_VALUES: dict[str, tuple[int, int]] = {
    "ON": (134, 7),
    "OFF": (134, 0),
    "QUIT": (0, 0),
    "RUN": (0, 1),
    "NEW": (0, 2),
    "PSAVE": (1004, 2),
    "POSSAVE": (1004, 4),
    "LS": (1031, 1),
    "RS": (1031, 2),
    "LF": (1031, 4),
    "RF": (1031, 8),
    "H": (1031, 16),
    "POS0": (1043, 1),
    "POSR": (1043, 2),
}

#: Bit address -> (P number, bit mask, inverted).  I1..I16 read bits of P1300/P1301; J1..J5
#: are the inverse of the P1013 "open" bits (§4.8.3.2, spec §3.4).
BIT_ADDRESSES: dict[str, tuple[int, int, bool]] = {
    **{f"I{i}": (1300, 1 << (i - 1), False) for i in range(1, 9)},
    **{f"I{i}": (1301, 1 << (i - 9), False) for i in range(9, 17)},
    "J1": (1013, 8, True),  # reference switch
    "J2": (1013, 2, True),  # limit switch left
    "J3": (1013, 1, True),  # limit switch right
    "J4": (1013, 4, True),  # STOP switch
    "J5": (1013, 128, True),  # service switch
}

#: Factory / power-on value of every parameter that has one (user units, default weighting).
FACTORY_DEFAULTS: dict[int, Number] = {n: d.default for n, d in PARAMETERS.items() if d.default is not None}

#: Parameters stored by PSAVE (P1004=2) unconditionally.
SAVED: frozenset[int] = frozenset(n for n, d in PARAMETERS.items() if d.saved)
#: Parameters stored by PSAVE only with P1117=1, and by P1004=5 (W, R0..R5).
SAVED_WITH_P1117: frozenset[int] = frozenset(n for n, d in PARAMETERS.items() if d.saved_with_p1117)
#: Stored by POSSAVE (P1004=4) and restored at power-on.
POSSAVE_PARAMS: frozenset[int] = frozenset({51})
#: Weighted parameters (converted via P76 / P44 / P160).
WEIGHTED: frozenset[int] = frozenset(n for n, d in PARAMETERS.items() if d.weighted)

_TOKEN = re.compile(r"P\s*([0-9]+)")


def lookup(token: str) -> ParamDef:
    """Resolve ``P91`` / ``p 91`` / ``91`` / ``V`` / ``wa`` to its definition; ``KeyError`` if
    unknown."""
    key = str(token).strip().upper()
    m = _TOKEN.fullmatch(key)
    if m:
        return PARAMETERS[int(m.group(1))]
    if key.isascii() and key.isdigit():
        return PARAMETERS[int(key)]
    return PARAMETERS[ALIASES[key]]


# ============================================================================================
# Variant tables
# ============================================================================================
DEFAULT_VARIANT = ("06", "85")  # SERS 06.85 V04 (spec §1 SIM-CHOICE)

#: P1010 maximum [mA] per current class (§4.8.6.1 table; "04" from the newer-series columns,
#: §1.2 says 5.6 A for SERS 04).  "06" = 8400 (default variant).
CURRENT_MAX_MA: dict[str, int] = {
    "01": 1400,
    "02": 2800,
    "03": 4200,
    "04": 4000,
    "06": 8400,
    "08": 8400,
    "12": 14500,
}
#: The second group of columns of the §4.8.6.1 table (newer series): 04 4000, 06 6000, 08 8400.
CURRENT_MAX_MA_NEW_SERIES: dict[str, int] = {"04": 4000, "06": 6000, "08": 8400}

#: P1034 value per current class (§4.8.6.1, examples SERS 01.60 .. SERS 12.120).
CURRENT_RANGE_P1034: dict[str, int] = {"01": 1, "02": 2, "03": 3, "04": 5, "06": 6, "08": 6, "12": 12}

#: Supply class -> (U_V max supply, U_W pre-warning, U_B undervoltage error, U_L shut-off) [VDC]
#: (§2.1.4 table).
SUPPLY_THRESHOLDS: dict[str, tuple[int, int, int, int]] = {
    "24": (36, 19, 18, 16),
    "60": (70, 46, 43, 32),
    "85": (85, 46, 43, 32),
    "120": (120, 58, 50, 36),
    "240": (240, 120, 100, 80),
}
#: Supply class -> nominal supply range [VDC] (§5 "Versorgungsspannung").
SUPPLY_NOMINAL_RANGE: dict[str, tuple[int, int]] = {
    "24": (20, 40),
    "60": (50, 70),
    "85": (50, 85),
    "120": (60, 120),
    "240": (120, 240),
}

# ============================================================================================
# SERS-Programmer masks (§4.8.6.15)
# ============================================================================================
#: Mask parameter -> the 16 parameters released by bit values 1, 2, 4, ... 32768.
PARAMETER_MASKS: dict[int, tuple[int, ...]] = {
    1060: (0, 1, 2, 11, 12, 41, 42, 44, 47, 51, 76, 91, 100, 101, 102, 103),
    1061: (108, 121, 122, 123, 134, 138, 147, 160, 265, 336, 403, 1001, 1002, 1003, 1004, 1005),
    1062: (1006, 1007, 1008, 1009, 1010, 1011, 1012, 1013, 1014, 1015, 1016, 1017, 1018, 1019, 1020, 1021),
    1063: (1022, 1023, 1024, 1025, 1026, 1027, 1028, 1029, 1030, 1031, 1032, 1033, 1034, 1035, 1036, 1037),
    1064: (1038, 1039, 1040, 1041, 1042, 1043, 1044, 1045, 1046, 1047, 1050, 1051, 1052, 1053, 1054, 1055),
    1065: (1056, 1057, 1058, 1059, 1060, 1061, 1062, 1063, 1064, 1065, 1066, 1070, 1071, 1072, 1073, 1080),
    1066: (1081, 1082, 1083, 1084, 1085, 1092, 1093, 1094, 1095, 1096, 1097, 1098, 1099, 1100, 1101, 1102),
    1067: (1103, 1110, 1111, 1112, 1113, 1114, 1115, 1116, 1117, 1118, 1119, 1120, 1121, 1122, 1123, 1124),
    1068: (1125, 1126, 1201, 1202, 1203, 1204, 1205, 1206, 1207, 1208, 1209, 1210, 1211, 1212, 1213, 1214),
}
#: Program mask parameter -> the 16 labels released by bit values 1 .. 32768.
PROGRAM_MASKS: dict[int, tuple[int, ...]] = {
    1070 + i: tuple(range(16 * i + 1, 16 * i + 17)) for i in range(4)
}

del _i, _n, _name, _en, _alias, _doc, _d


#: Parameters that are kept and answered but have no effect in the simulator (the generated
#: reference marks them "stored"); every other parameter has the effect the manual gives it.
STORED_ONLY: frozenset[int] = frozenset()
