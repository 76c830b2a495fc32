"""SERS weighting ("Wichtung") system: user units <-> motor increments, and number formatting.

Sources: manual §4.8.4.6 "Wichtung (Skalierung) der Betriebsparameter" (seed lines 2811–2872:
tables of P76 / P44 / P160 with unit and number of decimals), §4.8.4.7 "Mechanik - Getriebe,
Vorschubkonstante" (P121, P122, P123), §1.2 (12800 micro-steps per motor revolution), §4.2
"Dezimalkonstante" (number syntax); spec §5.1 (conversion table) and §3.7 / §7 G-QUERYFMT
(query formatting).

Conversion (g = P121/P122 motor revolutions per load revolution, f = P123 distance per load
revolution, in mm or in according to the position weighting, spec G-UNITS; a speed or an
acceleration weighted in the other length unit -- in/min or in/s² while P123 is in mm, or mm/min
or mm/s² while it is in inches -- takes f in its own unit, 1 in = 25.4 mm: §4.8.4.6 gives each
weighting its unit):

=====================  ==========================================
position 0             inc = u
position 64            inc = u * g
position 2             inc = u * 12800/360
position 66            inc = u * g * 12800/360
position 1, 17         inc = u * g * 12800 / f
velocity 0, 2          inc/s = u * 12800/60
velocity 64, 66        inc/s = u * g * 12800/60
velocity 1, 17         inc/s = u/60 * g * 12800 / f
acceleration 0, 2      inc/s² = u * 12800/(2 pi)
acceleration 64, 66    inc/s² = u * g * 12800/(2 pi)
acceleration 1, 17     inc/s² = u * g * 12800 / f
=====================  ==========================================

Everything here is pure: no I/O, no device state.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from decimal import ROUND_HALF_UP, Context, Decimal

__all__ = [
    "INCREMENTS_PER_REV",
    "INT32_MAX",
    "INT32_MIN",
    "POSITION_WEIGHTINGS",
    "VELOCITY_WEIGHTINGS",
    "ACCEL_WEIGHTINGS",
    "WEIGHTING_CODES",
    "Scaling",
    "format_query",
    "query_formatter",
    "format_fixed",
    "parse_number",
    "quantize",
]

#: Micro-steps ("Inkremente") per motor revolution, fixed (§1.2, §4.8.4.6).
INCREMENTS_PER_REV = 12800
INT32_MAX = 2**31 - 1
INT32_MIN = -(2**31)
#: Largest W at incremental weighting (§4.8.4.2 P47: "Inkremental : -2147483639 bis
#: +2147483639 (Inkmente/Schritte)"), a little short of 2^31 - 1.
INCREMENTAL_MAX = 2147483639
#: Millimetres per inch: the translational weightings 17 (in, in/min, in/s²) against 1 (mm ...).
MM_PER_INCH = 25.4

#: P76 code -> (unit string as sent, decimals) (§4.8.4.6 table "Wichtungsart für Lagedaten").
POSITION_WEIGHTINGS: dict[int, tuple[str, int]] = {
    0: ("inkr", 0),  # incremental, motor
    64: ("inkr", 0),  # incremental, load
    2: ("°", 4),  # rotational, motor (default)
    66: ("°", 4),  # rotational, load
    1: ("mm", 4),  # translational, load
    17: ("in", 6),  # translational (inch), load
}

#: P44 code -> (unit, decimals) (§4.8.4.6 table "Wichtungsart Geschwindigkeitsdaten").
VELOCITY_WEIGHTINGS: dict[int, tuple[str, int]] = {
    0: ("U/min", 4),
    64: ("U/min", 4),
    2: ("U/min", 4),
    66: ("U/min", 4),
    1: ("mm/min", 3),
    17: ("in/min", 5),
}

#: P160 code -> (unit, decimals) (§4.8.4.6 table "Wichtungsart Beschleunigungsdaten").
ACCEL_WEIGHTINGS: dict[int, tuple[str, int]] = {
    0: ("rad/s²", 3),
    64: ("rad/s²", 3),
    2: ("rad/s²", 3),
    66: ("rad/s²", 3),
    1: ("mm/s²", 3),
    17: ("in/s²", 5),
}

#: The six valid weighting codes (same set for P76, P44, P160); anything else -> errno 3.
WEIGHTING_CODES: frozenset[int] = frozenset(POSITION_WEIGHTINGS)

_LOAD = frozenset({64, 66})  # rotational/incremental referred to the load: gear included
_TRANSLATIONAL = frozenset({1, 17})  # gear and feed constant always included


def _mm_per(code: int) -> float:
    """Millimetres in the length unit of a translational weighting code (§4.8.4.6: 17 is inch)."""
    return MM_PER_INCH if code == 17 else 1.0


class Scaling:
    """Unit conversion for one set of weighting parameters (P76, P44, P160, P121, P122, P123).

    Increments are floats here; the device rounds positions to whole increments itself.
    """

    def __init__(
        self,
        p76: int = 2,
        p44: int = 2,
        p160: int = 2,
        p121: float = 1,
        p122: float = 1,
        p123: float = 1,
    ) -> None:
        for name, code in (("P76", p76), ("P44", p44), ("P160", p160)):
            if code not in WEIGHTING_CODES:
                raise ValueError(f"{name}={code} is not a valid weighting code")
        if p121 <= 0 or p122 <= 0 or p123 <= 0:
            raise ValueError("P121, P122 and P123 must be > 0")
        self.p76, self.p44, self.p160 = p76, p44, p160
        self.p121, self.p122, self.p123 = p121, p122, p123
        g = p121 / p122
        f = p123
        n = INCREMENTS_PER_REV
        f_mm = f * (MM_PER_INCH if p76 == 17 else 1)  # P123 in the position length unit (G-UNITS)
        # increments per user unit
        if p76 == 0:
            self.pos_factor = 1.0
        elif p76 == 64:
            self.pos_factor = g
        elif p76 == 2:
            self.pos_factor = n / 360
        elif p76 == 66:
            self.pos_factor = g * n / 360
        else:  # 1, 17
            self.pos_factor = g * n / f
        # (inc/s) per user unit
        if p44 in (0, 2):
            self.vel_factor = n / 60
        elif p44 in _LOAD:
            self.vel_factor = g * n / 60
        else:  # 1 mm/min, 17 in/min: f in the speed's own length unit
            self.vel_factor = g * n * _mm_per(p44) / (60 * f_mm)
        # (inc/s²) per user unit
        if p160 in (0, 2):
            self.acc_factor = n / (2 * math.pi)
        elif p160 in _LOAD:
            self.acc_factor = g * n / (2 * math.pi)
        else:  # 1 mm/s², 17 in/s²: f in the acceleration's own length unit
            self.acc_factor = g * n * _mm_per(p160) / f_mm

    # --- units and decimals -------------------------------------------------------------------
    @property
    def gear(self) -> float:
        """g = P121/P122 (motor revolutions per load revolution)."""
        return self.p121 / self.p122

    @property
    def pos_unit(self) -> str:
        return POSITION_WEIGHTINGS[self.p76][0]

    @property
    def pos_decimals(self) -> int:
        return POSITION_WEIGHTINGS[self.p76][1]

    @property
    def vel_unit(self) -> str:
        return VELOCITY_WEIGHTINGS[self.p44][0]

    @property
    def vel_decimals(self) -> int:
        return VELOCITY_WEIGHTINGS[self.p44][1]

    @property
    def acc_unit(self) -> str:
        return ACCEL_WEIGHTINGS[self.p160][0]

    @property
    def acc_decimals(self) -> int:
        return ACCEL_WEIGHTINGS[self.p160][1]

    @property
    def length_unit(self) -> str:
        """The unit of the feed constant P123 (§4.8.4.7, §4.7 "wie z.B. die Vorschubkonstante wird
        die Einheit mitgesendet"): inch with P76=17, else mm (the manual's example 'P…=150mm'
        at the default weighting)."""
        return "in" if self.p76 == 17 else "mm"

    @property
    def translational(self) -> bool:
        """True if positions are weighted translationally (P76 = 1 or 17): P123 is then in pos_unit."""
        return self.p76 in _TRANSLATIONAL

    def unit(self, kind: str) -> str:
        """Unit string for a parameter kind ("position", "velocity", "acceleration"; else "")."""
        return {"position": self.pos_unit, "velocity": self.vel_unit, "acceleration": self.acc_unit}.get(
            kind, ""
        )

    def decimals(self, kind: str) -> int:
        """Decimals for a weighted parameter kind; raises KeyError for other kinds."""
        return {
            "position": self.pos_decimals,
            "velocity": self.vel_decimals,
            "acceleration": self.acc_decimals,
        }[kind]

    # --- conversions --------------------------------------------------------------------------
    def pos_to_inc(self, u: float) -> float:
        return u * self.pos_factor

    def inc_to_pos(self, inc: float) -> float:
        return inc / self.pos_factor

    def vel_to_incps(self, u: float) -> float:
        return u * self.vel_factor

    def incps_to_vel(self, v: float) -> float:
        return v / self.vel_factor

    def acc_to_incps2(self, u: float) -> float:
        return u * self.acc_factor

    def incps2_to_acc(self, a: float) -> float:
        return a / self.acc_factor

    def to_internal(self, kind: str, u: float) -> float:
        """User value -> inc / inc/s / inc/s² for a weighted kind."""
        if kind == "position":
            return self.pos_to_inc(u)
        if kind == "velocity":
            return self.vel_to_incps(u)
        if kind == "acceleration":
            return self.acc_to_incps2(u)
        raise KeyError(kind)

    def from_internal(self, kind: str, value: float) -> float:
        """inc / inc/s / inc/s² -> user value for a weighted kind."""
        if kind == "position":
            return self.inc_to_pos(value)
        if kind == "velocity":
            return self.incps_to_vel(value)
        if kind == "acceleration":
            return self.incps2_to_acc(value)
        raise KeyError(kind)

    def pos_range(self) -> tuple[float, float]:
        """Representable position range in user units.

        The tighter of the 32-bit fixed-point range (±(2^31-1)/10^decimals) and the 32-bit
        increment range.  Reproduces the manual's W ranges (§4.8.4.2): rotational ±214748.3647°,
        translational ±167772.1599 mm (gear 1:1, P123=1) and incremental ±2147483639 increments
        ("Inkremental : -2147483639 bis +2147483639"; the fixed-point bound of the weightings
        without decimals is that number, not 2^31 - 1).
        """
        made = self.__dict__.get("_pos_range")
        if made is not None:  # (a scaling never changes: P76 … P123 written make a new one)
            return made
        d = self.pos_decimals
        scale = 10**d
        fixed = (INT32_MAX if d else INCREMENTAL_MAX) / scale
        inc = INT32_MAX / self.pos_factor
        hi = math.floor(min(fixed, inc) * scale) / scale
        self._pos_range = (-hi, hi)
        return -hi, hi

    def __repr__(self) -> str:
        return (
            f"Scaling(p76={self.p76}, p44={self.p44}, p160={self.p160}, "
            f"p121={self.p121}, p122={self.p122}, p123={self.p123})"
        )


# --- numbers ----------------------------------------------------------------------------------
#: (compiled by :mod:`re` at the first number parsed, not by every start: issue 31)
_NUMBER = r"-?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)"


def parse_number(text: str) -> float:
    """Parse a SERS decimal constant (§4.2 "Dezimalkonstante", "Datum" = [-] constant).

    Digits with an optional ``.`` (``10``, ``10.75``, ``10.``), a leading ``.`` is allowed
    (``.5``), an optional leading ``-``.  No ``+``, no comma, no exponent, no whitespace:
    anything else raises ``ValueError``.
    """
    if not isinstance(text, str) or re.fullmatch(_NUMBER, text) is None:
        raise ValueError(f"not a SERS decimal constant: {text!r}")
    return float(text)


#: Room for every finite float on a fixed-point grid: up to 309 integer digits and the decimals (the
#: default context's 28 digits are too few for a constant like W=2748332147483632147483639, stored as
#: typed in a program and rendered with 4 decimals by LIST).
_WIDE = Context(prec=360)


def _on_grid(value: float, decimals: int) -> Decimal:
    """*value* rounded to the fixed-point grid of *decimals* places (half away from zero), exactly."""
    if not math.isfinite(value):
        raise ValueError(f"not a finite number: {value!r}")
    return Decimal(repr(float(value))).quantize(Decimal(1).scaleb(-decimals), rounding=ROUND_HALF_UP, context=_WIDE)


def quantize(value: float, decimals: int) -> float:
    """Round *value* to the fixed-point grid of *decimals* places (half away from zero)."""
    result = float(_on_grid(value, decimals))
    return 0.0 if result == 0 else result


def format_fixed(value: float, decimals: int) -> str:
    """Fixed-point rendering with all decimals, e.g. ``format_fixed(500, 4) == "500.0000"``."""
    q = _on_grid(value, decimals)
    if q == 0:
        q = abs(q)  # no "-0.0000"
    return f"{q:f}"


def format_query(value: float, decimals: int, unit: str = "") -> str:
    """Query-answer rendering (spec §3.7, G-QUERYFMT): trailing zeros and a trailing ``.``
    dropped, unit appended without a space: ``2.5mm``, ``150mm``, ``0°``."""
    text = format_fixed(value, decimals)
    if "." in text:
        text = text.rstrip("0").rstrip(".")
    if text in ("-0", ""):
        text = "0"
    return text + unit


def _format_query_fixed(value: float, decimals: int, unit: str = "") -> str:
    """:func:`format_query` with all decimals kept (G-QUERYFMT ⚙ ``query_fixed_decimals``): ``2.5000mm``."""
    return format_fixed(value, decimals) + unit


#: The query renderings by (``query_fixed_decimals``, ``query_units``) (spec G-QUERYFMT ⚙).
_QUERY_FORMATS: dict[tuple[bool, bool], Callable[[float, int, str], str]] = {
    (False, True): format_query,
    (True, True): _format_query_fixed,
    (False, False): lambda value, decimals, unit="": format_query(value, decimals),
    (True, False): lambda value, decimals, unit="": format_fixed(value, decimals),
}


def query_formatter(fixed_decimals: bool = False, units: bool = True) -> Callable[[float, int, str], str]:
    """How a query answers a weighted or ``fixed`` value (G-QUERYFMT): trailing zeros dropped
    and the unit appended (:func:`format_query`, the default); ⚙ ``query_fixed_decimals`` keeps
    all decimals, ⚙ ``query_units: false`` leaves the unit off."""
    return _QUERY_FORMATS[(fixed_decimals, units)]
