"""The machine parameters P1 … P98 (manual §2.2.3, §2.3.3, §2.3.6–§2.3.9, §2.3.14, §2.3.21,
§2.3.22, §2.4.4, §2.4.7, §2.4.9, §2.5, §2.6.2, §2.6.3; spec poselesta.md §3.9, §4.8).

Every number P1 … P98 but P79 (the diagnostic program) is stored (default 0) and round-trips;
the rows with a declared range have the effect the manual gives them: on the serial ports, the
buzzer, the strobes, the speeds and gains of the axes, the working field and the NC-Start.  The
values live in :class:`MachineParameters`, the kind's parameters part, read through named
accessors; the parameter catalogue P99 is how a transfer carries them (spec §3.9).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from devsim.core.nvram import NonVolatileMemory, numbered
from devsim.core.parameters import Param, Parameters, ParameterTable, accessor
from devsim.devices.poselesta.signals import AXES
from devsim.devices.poselesta.tape import Block, Formats

__all__ = ["CATALOGUE_FORMATS", "CATALOGUE_SCALE", "PARAMETERS", "MachineParameters", "check_parameter"]

#: The catalogue's value word P carries 3 decimals (spec §3.9, simulator-defined format).
CATALOGUE_SCALE = 1000
#: P75: which NC-Start counts (0 both, 1 the panel, 2 the external button V19/3).
NC_START_SOURCES = {0: ("panel", "external"), 1: ("panel",), 2: ("external",)}
#: P79 is the diagnostic program, not a parameter (manual §2.3.25).
DIAGNOSTIC_PROGRAM = 79
#: The first number (axis X) of each per-axis family; Y, Z, D follow.
LIMIT_PLUS, LIMIT_MINUS, GAIN, RAPID, MAX_FEED = 9, 13, 30, 44, 48


def _ranged(key: int, name: str, doc: str, section: str, minimum: float, maximum: float, default: float,
            attr: str, *, whole: bool = True, choices: tuple[int, ...] | None = None) -> Param:
    return Param(key, name, section, doc, type="int" if whole else "float", minimum=minimum, maximum=maximum,
                 choices=choices, default=default, attr=attr)


def _per_axis(first: int, name: str, doc: str, section: str, minimum: float, maximum: float, default: float,
              attr: str, *, whole: bool = True) -> list[Param]:
    return [_ranged(first + i, f"{name} {a.upper()}", doc.format(a=a.upper(), n=first + i), section, minimum,
                    maximum, default, f"{attr}_{a}", whole=whole) for i, a in enumerate(AXES)]


_RANGED: list[Param] = [
    _ranged(1, "mm/inch", "measuring system of the catalogues (0 = mm, 1 = inch)", "§2.3.14", 0, 1, 0,
            "catalogue_inch"),
    _ranged(67, "Summer", "buzzer V16/6 (0 = on, 1 = off)", "§2.4.9", 0, 1, 0, "buzzer_off"),
    _ranged(68, "Baud-Rate V6", "V6 baud rate code (0 = 110 … 5 = 4800)", "§2.6.2.3", 0, 5, 3, "v6_baud_code"),
    _ranged(69, "Code V6", "V6 code (0 = ISO, 1 = ASCII)", "§2.6.2.1–3", 0, 1, 0, "v6_code"),
    _ranged(70, "Baud-Rate V7", "V7 baud rate code (0 = 110 … 5 = 4800)", "§2.6.3", 0, 5, 3, "v7_baud_code"),
    _ranged(71, "Code V7", "V7 code (0 = ISO, 1 = ASCII)", "§2.6.3", 0, 1, 0, "v7_code"),
    _ranged(72, "t1 = t2", "strobe times t1 = t2 in ms (0 is taken as 1 ms)", "§2.4.7", 0, 99, 20, "strobe_ms"),
    *_per_axis(LIMIT_PLUS, "Software-Endschalter +", "software limit + {a}, mm from the reference mark", "§2.4.4", -99999,
               99999, 99999, "limit_plus", whole=False),
    *_per_axis(LIMIT_MINUS, "Software-Endschalter −", "software limit − {a}, mm from the reference mark", "§2.4.4", -99999,
               99999, -99999, "limit_minus", whole=False),
    *_per_axis(GAIN, "Verstärkung", "gain (Verstärkung) {a}: Kv = P{n} × kv_per_step", "§2.5", 1, 99, 10, "gain"),
    *_per_axis(RAPID, "Eilgang", "maximum speed = rapid {a}, mm/min (G00, V21/6)", "§2.3.8", 0, 9999, 6000, "rapid"),
    *_per_axis(MAX_FEED, "Vorschub", "maximum feed {a}, mm/min (100 % of the feed pot)", "§2.3.6", 0, 9999, 2000,
               "max_feed"),
    _ranged(64, "Eilgang-Override", "rapid influenced by the override pot (0 = no, 1 = yes)", "§2.3.22", 0, 1, 0,
            "rapid_override"),
    _ranged(75, "NC-Start", "NC-Start source (0 = both, 1 = front panel, 2 = external V19/3)", "§2.3.3", 0, 2, 0,
            "nc_start_source"),
    _ranged(76, "Handrad-Auswertung", "handwheel evaluation: increments per handwheel step (1, 2 or 4)", "§2.2.3",
            1, 4, 1, "handwheel_step", choices=(1, 2, 4)),
    _ranged(77, "Open-loop", "open-loop axes, bit mask X = 1, Y = 2, Z = 4, D = 8", "§2.3.9", 0, 15, 0,
            "open_loop_axes"),
    _ranged(90, "Satzabbruch", "block number N the program goes on at after a block abort V22/10 (POS III)",
            "§2.3.21", 0, 999, 0, "abort_block"),
]
_RANGED_KEYS = {row.key for row in _RANGED}
#: The catalogue's word formats on output: the parameters in mm (the software limits P9–P16) keep
#: their three decimals (spec §3.9: ``N9 P250.000``).
CATALOGUE_FORMATS = Formats(fractional=frozenset(row.key for row in _RANGED if row.type == "float"))

#: P1 … P98 without P79, by number: the ranged rows, and every other number stored and answered
#: without an effect (spec §4.8).
PARAMETERS = ParameterTable(
    sorted(
        [
            *_RANGED,
            *(Param(n, f"Maschinenparameter P {n}", "§2.6.2.3", f"machine parameter P{n}", type="float",
                    default=0.0, effect="stored")
              for n in range(1, 99) if n != DIAGNOSTIC_PROGRAM and n not in _RANGED_KEYS),
        ],
        key=lambda row: row.key,
    ),
    prefix="P",
    name="machine parameter",
)


def check_parameter(number: int, value: float) -> None:
    """Refuse a parameter number or value the control would not take (ValueError)."""
    row = PARAMETERS.get(number)
    if row is None:
        raise ValueError(f"P{number}: parameters are P1 … P98 (P79 is the diagnostic program)")
    if not math.isfinite(value):
        raise ValueError(f"P{number}: not a finite number")
    if row.minimum is not None and row.maximum is not None:
        whole = row.type == "int"
        if not row.minimum <= value <= row.maximum or whole and not float(value).is_integer():
            kind = "a whole number" if whole else "a number"
            raise ValueError(f"P{number}: {value:g} is not {kind} in {row.minimum:g} … {row.maximum:g}")
        if row.choices is not None and value not in row.choices:
            raise ValueError(f"P{number}: {value:g} is not one of {', '.join(map(str, row.choices))}")


class MachineParameters(Parameters):
    """The parameter values of one control, kept in its memory (manual §2.6.2.3; spec §4.8):
    the configured values at the first power-on, the stored ones afterwards; the catalogue P99
    read in acts after its M30 (spec §3.9)."""

    catalogue_inch = accessor(1, "P1: the catalogues are in inch")
    buzzer_off = accessor(67, "P67: 1 = the buzzer is off")
    v6_baud_code = accessor(68, "P68: the baud rate code of V6")
    v6_code = accessor(69, "P69: the code of V6 (0 = ISO)")
    v7_baud_code = accessor(70, "P70: the baud rate code of V7")
    v7_code = accessor(71, "P71: the code of V7 (0 = ISO)")
    strobe_ms = accessor(72, "P72: t1 = t2 in ms")
    rapid_override = accessor(64, "P64: 1 = the override pot acts on rapid")
    nc_start_source = accessor(75, "P75: 0 both, 1 the panel, 2 the external button")
    handwheel_step = accessor(76, "P76: increments per handwheel detent")
    open_loop_axes = accessor(77, "P77: the open-loop axes as a bit mask")
    abort_block = accessor(90, "P90: the block a block abort goes on at")

    def __init__(self, nvram: NonVolatileMemory, initial: Mapping[int, float]) -> None:
        super().__init__(PARAMETERS)
        self._nvram = nvram
        self._initial = dict(initial)
        self._pending: dict[int, float] = {}
        self.load()

    # -- per axis ---------------------------------------------------------------------------------
    def limits(self, axis: str) -> tuple[float, float]:
        """P13–P16 (−) and P9–P12 (+): the software limits in mm from the reference mark."""
        i = AXES.index(axis)
        return self.values[LIMIT_MINUS + i], self.values[LIMIT_PLUS + i]

    def gain(self, axis: str) -> float:
        """P30–P33: the position loop gain in steps."""
        return self.values[GAIN + AXES.index(axis)]

    def rapid(self, axis: str) -> float:
        """P44–P47: the rapid of an axis in mm/min."""
        return self.values[RAPID + AXES.index(axis)]

    def max_feed(self, axis: str) -> float:
        """P48–P51: the maximum feed of an axis in mm/min."""
        return self.values[MAX_FEED + AXES.index(axis)]

    def nc_start_counts(self, source: str) -> bool:
        """P75: does an NC-Start from ``source`` (``panel``, ``external``) count?"""
        return source in NC_START_SOURCES.get(int(self.nc_start_source), ())

    def is_open_loop(self, axis: str) -> bool:
        """P77 marks ``axis`` as an open-loop axis."""
        return bool(int(self.open_loop_axes) >> AXES.index(axis) & 1)

    def baud_code(self, port: str) -> int:
        """P68 (V6) or P70 (V7): the port's baud rate code."""
        return int(self.v6_baud_code if port == "v6" else self.v7_baud_code)

    def baud_code_key(self, port: str) -> int:
        """The number of the port's baud rate parameter (P68, P70)."""
        return PARAMETERS.by_attr(f"{port}_baud_code").key  # type: ignore[return-value]

    def iso(self, port: str) -> bool:
        """P69 (V6) or P71 (V7) = 0: the port uses ISO code."""
        return (self.v6_code if port == "v6" else self.v7_code) == 0

    # -- memory -----------------------------------------------------------------------------------
    def load(self) -> None:
        """Power-on: the stored values, or the configured ones before anything was stored."""
        self.reset()
        stored = self._nvram.get("params")
        if "params" not in self._nvram:  # (nothing saved yet, or a wiped memory)
            self.values.update({int(k): float(v) for k, v in self._initial.items()})
        elif not stored:  # (null or {} read as nothing saved, or as no parameter, before)
            raise ValueError(f"the stored parameters {stored!r:.40} are none: a save writes every parameter")
        else:
            # a key is the number as save writes it (str(n)), else the memory is refused: int() took
            # '٤١', '４１', '+41', ' 41', '041' and '4_1' for P41 (a second P41 beside "41").
            # [SIM-CHOICE] A number no parameter has is ignored, as before.
            kept = {n: v for n, v in numbered(stored, "parameter").items() if n in self.table}
            for number, value in kept.items():
                # a stored value that is no finite number (a hand edit: "nan", "1e999", true)
                # refuses the memory at the start, the file named (UnfitMemory); before, float()
                # took "nan" and the next save raised PoisonedMemory.  A value is one the control
                # takes (check_parameter: an entry, a catalogue block, the config), or 0, which a
                # catalogue read-in that never reached its M30 leaves in P30-P33 and P76 on purpose;
                # before, P68 = 7 (no baud rate code) or P30 = 1e30 loaded and were served.
                if type(value) not in (int, float) or not math.isfinite(value):
                    raise ValueError(f"P{number}: {value!r} is no finite number")
                if value != 0:
                    check_parameter(number, value)
            self.values.update({number: float(value) for number, value in kept.items()})

    def save(self) -> None:
        self._nvram.put("params", {str(n): v for n, v in sorted(self.values.items())})

    def write(self, number: int, value: float) -> None:
        """A value entered (panel, control API): checked as the control checks it, then stored."""
        check_parameter(number, value)
        self.set(number, value, check=False)
        self.save()

    # -- the catalogue P99 (spec §3.9) ---------------------------------------------------------------
    def catalogue_blocks(self) -> list[Block]:
        """The catalogue as blocks ``N<number> P<value>``, P1 … P98 without P79 (spec §3.9, a
        simulator-defined format: the original is not documented)."""
        return [Block(number, (("P", round(self.values.get(number, 0.0) * CATALOGUE_SCALE)),))
                for number in PARAMETERS.rows]

    def begin_catalogue(self) -> None:
        """A catalogue read-in starts: the whole catalogue is 0 first (§2.6.2.3, P68–P71 too)."""
        for number in list(self.values):
            self.values[number] = 0.0
        self.save()
        self._pending = {}

    def store_catalogue(self, block: Block) -> str | None:
        """A catalogue block read in: N selects the parameter, P is its value; returns why it
        cannot be taken (the read-in then fails), or None."""
        value = block.value("P")
        if value is None:
            return None  # a block without a value changes nothing
        try:
            check_parameter(block.number, value / CATALOGUE_SCALE)
        except ValueError as exc:
            return str(exc)
        self._pending[block.number] = value / CATALOGUE_SCALE
        return None

    def commit_catalogue(self) -> None:
        """The read-in ended with M30: the values act now (spec §3.9)."""
        self.values.update(self._pending)
        self.save()
