"""SERS parameter table: every P number of the manual, with aliases, ranges, defaults and access.

Sources: manual §4.7 "Parameterübersicht" (seed lines 1730–1800: the list of all parameters),
§4.8 "SERS Parameter" (seed lines 1847–4020: one heading per parameter -- the heading is the
designation returned by ``P<n>??``), §4.2 "Adresse" (aliases), §2.1.4 (supply thresholds),
§4.8.6.1 (P1010 maximum per version), §4.8.6.15 (SERS-Programmer masks); transcribed in spec
§3.4, §4.5, §4.6, §4.8.1–§4.8.7 and §2.7.

Conventions
-----------
* Each row is a kit :class:`~devsim.core.parameters.Param` (key = the P number, ``name`` the German
  designation, ``doc`` the English gloss); the SERS's own facts below are in its ``extra``
  (:data:`~devsim.devices.sers.paramdef.EXTRA`): ``kind``, the errnos, ``min_exclusive``,
  ``saved_with_p1117``, ``length_unit``, ``commands`` and the manual's ``note``.
* Values are in user units.  Weighted kinds (``position``/``velocity``/``acceleration``) follow
  P76 / P44 / P160 (see :mod:`.units`); their ``minimum``/``maximum`` are given in the default
  weighting (°, U/min, rad/s²) where the manual states a range, else ``None`` -- the device
  re-checks weighted ranges after conversion (e.g. :meth:`.units.Scaling.pos_range`).
* ``fixed`` = fixed number of decimals independent of weighting: D/D2 (1), P1139 (1),
  P1054/P1144 (5), ADC (3), P123 (4, unit = position length unit), X and R0..R5 (3, spec
  G-ARITH).
* ``min_exclusive`` marks ranges of the form "> minimum" (V, P103, P123).
* The errnos of a refused write are the row's (:meth:`.access.ParameterAccess.write_param` reads
  them, before any parameter's own write runs): ``too_large_errno`` / ``too_small_errno`` for a
  value out of range (default 1 "zu groß" / 2 "zu klein", the manual's "Parameterwert zu groß",
  §4.8.3.1 P12 value 16); ``invalid_errno`` for a value not in ``choices`` (default 3
  "ungültig"; P1014: 80 "unbekannter Positioniermodus"; P0 / P1004: 82 "ungültiger EEPROM Modus
  Wert"); ``write_errno`` for a write to a read-only parameter: 105 "Wert kann nicht geschrieben
  werden" (the counterpart of 106 "Wert kann nicht gelesen werden", which a read of a write-only
  parameter gets), except P1034, which the manual does not call read-only but says "darf nicht
  geändert werden - wird werkseitig eingestellt" (§4.8.6.1): 12 "Zugriff verweigert".
* ``saved`` = "E" in the spec (stored by PSAVE); ``effect`` is ``stored`` for :data:`STORED_ONLY`.  W (P47) and R0..R5 are "S": stored only with
  P1117=1 (``saved_with_p1117``).  P51 is stored by POSSAVE only (:data:`POSSAVE_PARAMS`).
* ``default`` = factory/power-on value ([M] manual or [SIM] spec choice); for variant-dependent
  values it is the default variant SERS 06.85 (P1010 max 8400 mA, P1034 = 6).
* Command keywords (ON/OFF, RUN/QUIT/NEW, PSAVE/POSSAVE, LS/RS/LF/RF/H, POS0/POSR, VER) and bit
  addresses (I1..I16, J1..J5) are not simple aliases: see :data:`COMMAND_VALUES` and
  :data:`BIT_ADDRESSES`; they are listed in the ``commands`` field of their parameter but not
  in :data:`ALIASES`.
"""

from __future__ import annotations

from collections.abc import Mapping

import msgspec

from devsim.core.parameters import Param, ParameterTable
from devsim.devices.sers.constants import WEIGHTED_KINDS
from devsim.devices.sers.paramdef import Kind, Number
from devsim.devices.sers.params_io import ROWS as _IO
from devsim.devices.sers.params_misc import ROWS as _MISC
from devsim.devices.sers.params_motion import ROWS as _MOTION

__all__ = [
    "Kind",
    "PARAMETER_TABLE",
    "PARAMETERS",
    "ALIASES",
    "KIND",
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
    "STORED_ONLY",
]

#: Parameters that are kept and answered but have no effect in the simulator (their rows'
#: ``effect`` is ``stored``): found by looking for every P number in the model's code and
#: reading the manual's section for those never used.  SERS-Programmer masks and password,
#: fieldbus settings, commutation and chopper settings have no effect a host could see; the
#: others have one the manual describes and the simulator lacks (see the session notes).
STORED_ONLY: frozenset[int] = frozenset(
    {
        1009, 1034, 1038, 1056, 1059, *range(1060, 1069), *range(1070, 1074), 1094, 1097,
        1136, 1142, 1147, 1149, 1150, 1153, 1154, 1155, 1157, 1158, 1159, 1161,
    }
)

#: The SERS's parameters as kit rows, by P number (aliases V, A, W …; ``P91``, ``p 91``, ``91``).
PARAMETER_TABLE = ParameterTable(
    sorted(
        (msgspec.structs.replace(row, effect="stored") if row.key in STORED_ONLY else row for row in (*_IO, *_MOTION, *_MISC)),
        key=lambda row: row.key,
    ),
    prefix="P",
)

#: P number -> row.
PARAMETERS: Mapping[int, Param] = PARAMETER_TABLE.rows  # type: ignore[assignment]

#: P number -> how its value is kept and shown (``int``, a weighting, ``fixed``).
KIND: dict[int, Kind] = {n: d.extra["kind"] for n, d in PARAMETERS.items()}

#: Upper-case alias -> P number (simple aliases only; see module docstring).
ALIASES: dict[str, int] = {alias: d.key for d in PARAMETERS.values() for alias in d.aliases}

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
FACTORY_DEFAULTS: dict[int, Number] = PARAMETER_TABLE.defaults()  # type: ignore[assignment]

#: Parameters stored by PSAVE (P1004=2) unconditionally.
SAVED: frozenset[int] = frozenset(PARAMETER_TABLE.saved())  # type: ignore[arg-type]
#: Parameters stored by PSAVE only with P1117=1, and by P1004=5 (W, R0..R5).
SAVED_WITH_P1117: frozenset[int] = frozenset(n for n, d in PARAMETERS.items() if d.extra["saved_with_p1117"])
#: Stored by POSSAVE (P1004=4) and restored at power-on.
POSSAVE_PARAMS: frozenset[int] = frozenset({51})
#: Weighted parameters (converted via P76 / P44 / P160).
WEIGHTED: frozenset[int] = frozenset(n for n, kind in KIND.items() if kind in WEIGHTED_KINDS)

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

