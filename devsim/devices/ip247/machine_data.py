"""The IP247's machine-data record and its checks (manual §6.3.8.1, §2.5, §7.2.1; spec ip247.md
§3.4.1, §4.4, §4.8, §4.9, §5.2, §5.3; vectors §6.1–§6.3).

Pure: a record is 70 words (16 bit, big-endian in S5 order), :func:`decode` reads it into
:class:`MachineData`, :func:`encode` writes it back, :func:`check` gives the machine-data error
number the module writes into DR n+4 (0 = error-free), first failure winning in the order the
spec fixes.  :class:`Ramp` is the exponential frequency ramp the data define.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import msgspec

from devsim.core.kit import Command, Table
from devsim.core.words import signed32
from devsim.devices.ip247.tables import MD_ERRORS

__all__ = [
    "LIMIT", "RECORD_WORDS", "RESERVED", "MachineData", "Ramp", "check", "decode", "encode", "record_db", "stored",
]

RECORD_WORDS = 70
LIMIT = 99_999_999  # ±100 m in base units
#: Words n+48 … n+69: reserved, kept as the host wrote them.
RESERVED = slice(48, RECORD_WORDS)


def _signed(high: int, low: int) -> int:
    return signed32(high << 16 | low)


def _words(value: int) -> tuple[int, int]:
    value &= 0xFFFF_FFFF
    return value >> 16, value & 0xFFFF


class MachineData(msgspec.Struct, frozen=True):
    """One axis's machine data (spec §3.4.1), values as the record carries them."""

    db: int  # DR n+2
    module: int  # DL n+3
    axis: int  # DR n+3
    unit: int  # DL n+4: 1 mm, 2 0.1 inch, 3 degree
    error: int  # DR n+4 (written by the module)
    f_max: int  # Hz
    f_ss: int  # Hz
    a: int  # frequency increase, mHz/ms
    pulse_us: int
    pulse_polarity: int  # DR n+12: 00H negative edge, 40H positive edge
    patterns: int  # current patterns (Bestromungsmuster)
    pulses_per_rev: int
    gear: int  # base units per motor revolution
    jog1: int  # unit/min
    jog2: int
    step_velocity: int
    reference_velocity: int
    reference_sync: int  # n+25: 0 yes, 1 no
    reference_direction: int  # DR n+26: 00H forward, 20H backward
    reference: int  # base units
    limit_begin: int  # SW limit "Anfang" / range start
    limit_end: int  # SW limit "Ende" / range end
    limit_polarity: int  # n+33: 0 NO contact, 1 NC contact
    tool_length: int
    backlash: int
    zero_offsets: tuple[int, int, int, int]  # G54 … G57
    rotary: bool  # n+46 bit 7
    bcd: bool  # n+47 bit 0

    @property
    def zero_offset_1(self) -> int:
        """MD n+38/39, G54."""
        return self.zero_offsets[0]

    @property
    def zero_offset_2(self) -> int:
        """MD n+40/41, G55."""
        return self.zero_offsets[1]

    @property
    def zero_offset_3(self) -> int:
        """MD n+42/43, G56."""
        return self.zero_offsets[2]

    @property
    def zero_offset_4(self) -> int:
        """MD n+44/45, G57."""
        return self.zero_offsets[3]

    @property
    def resolution(self) -> float:
        """Base units per pulse: gear / pulses per revolution (spec §4.8)."""
        return self.gear / self.pulses_per_rev

    def frequency(self, velocity: float) -> float:
        """Hz of a velocity in unit/min (spec §5.2)."""
        return velocity * 1000 / (60 * self.resolution)

    @property
    def v_max(self) -> float:
        """Unit/min at f_max (spec §5.2)."""
        return self.f_max * self.resolution * 60 / 1000

    @property
    def ramp(self) -> Ramp:
        return Ramp(self.f_max, self.f_ss, self.a / 1000)


def record_db(words: list[int]) -> int:
    """The DB number a record names in its word n+2 (DR)."""
    return words[2] & 0xFF


def decode(words: list[int]) -> MachineData:
    """A 70-word record (spec §3.4.1); raises ValueError for another length."""
    if len(words) != RECORD_WORDS or words[0] != RECORD_WORDS:
        raise ValueError(f"a machine-data record has {RECORD_WORDS} words (word n = 70)")
    w = words

    def dd(i: int) -> int:
        return _signed(w[i], w[i + 1])

    return MachineData(
        db=w[2] & 0xFF, module=w[3] >> 8, axis=w[3] & 0xFF, unit=w[4] >> 8, error=w[4] & 0xFF,
        f_max=dd(5), f_ss=dd(7), a=dd(9), pulse_us=w[11], pulse_polarity=w[12] & 0xFF, patterns=w[13],
        pulses_per_rev=w[14], gear=dd(15), jog1=dd(17), jog2=dd(19), step_velocity=dd(21),
        reference_velocity=dd(23), reference_sync=w[25], reference_direction=w[26] & 0xFF, reference=dd(27),
        limit_begin=dd(29), limit_end=dd(31), limit_polarity=w[33], tool_length=dd(34), backlash=dd(36),
        zero_offsets=(dd(38), dd(40), dd(42), dd(44)), rotary=bool(w[46] & 0x80), bcd=bool(w[47] & 0x01),
    )


def encode(md: MachineData) -> list[int]:
    """The record of ``md`` (reserve words 0)."""
    words = [0] * RECORD_WORDS
    words[0], words[1], words[2] = RECORD_WORDS, 0x0044, 0x4200 | md.db
    words[3] = (md.module << 8) | md.axis
    words[4] = (md.unit << 8) | md.error
    for index, value in ((5, md.f_max), (7, md.f_ss), (9, md.a), (15, md.gear), (17, md.jog1), (19, md.jog2),
                         (21, md.step_velocity), (23, md.reference_velocity), (27, md.reference),
                         (29, md.limit_begin), (31, md.limit_end), (34, md.tool_length), (36, md.backlash),
                         *((38 + 2 * i, z) for i, z in enumerate(md.zero_offsets))):
        words[index], words[index + 1] = _words(value)
    words[11], words[12], words[13], words[14] = md.pulse_us, md.pulse_polarity, md.patterns, md.pulses_per_rev
    words[25], words[26], words[33] = md.reference_sync, md.reference_direction, md.limit_polarity
    words[46], words[47] = 0x80 if md.rotary else 0x00, 0x01 if md.bcd else 0x00
    return words


class Ramp(msgspec.Struct, frozen=True):
    """The exponential ramp (spec §5.3): the frequency jumps to f_ss, then rises as
    f(t) = f_ss + F (1 − e^(−t/τ)) with F = (f_max − f_ss) / 0.95 and τ = F / a."""

    f_max: float
    f_ss: float
    a: float  # Hz/ms

    @property
    def big_f(self) -> float:
        return (self.f_max - self.f_ss) / 0.95

    @property
    def tau(self) -> float:
        """Seconds."""
        return self.big_f / self.a / 1000 if self.a > 0 else math.inf

    def time_to(self, f_v: float) -> float:
        """Seconds from standstill to ``f_v`` (≤ f_max)."""
        return -self.tau * math.log(1 - (f_v - self.f_ss) / self.big_f)

    def pulses_to(self, f_v: float) -> float:
        """Pulses sent while accelerating to ``f_v`` (= while braking from it)."""
        t = self.time_to(f_v)
        return self.big_f * (t - self.tau * (1 - math.exp(-t / self.tau))) + self.f_ss * t


#: The order of the checks, the first failure wins (spec §4.4 [DECISION]).
CHECK_ORDER = (12, 11, 3, 22, 6, 2, 18, 5, 10, 9, 4, 17, 15, 7, 8, 19, 14, 20, 13, 16)


def check(md: MachineData, *, sys_module: int, limit_levels: tuple[bool, bool] = (True, True),
          ramp_table_fails: bool = False) -> int:
    """The machine-data error number (spec §4.4): 0, or the first failing check.
    ``limit_levels``: the two hardware limit inputs (True = 24 V) when the record arrives."""
    for number in CHECK_ORDER:
        if CHECKS[str(number)](md, sys_module, limit_levels, ramp_table_fails):
            return 21 if number == 7 and md.rotary else number
    return 0


def _velocity_bad(md: MachineData, velocity: int) -> bool:
    return not 1 <= velocity <= 65_000 or not 1 <= md.frequency(velocity) <= md.f_max


def _tau_bad(md: MachineData) -> bool:
    if not 20 <= md.a <= 2_599_999 or md.f_max <= md.f_ss:
        return True
    return not 5 <= md.ramp.tau * 1000 <= 2600


def _limits_bad(md: MachineData) -> bool:
    if md.rotary:
        return not md.limit_begin < md.limit_end
    return not (md.limit_begin < md.limit_end and abs(md.limit_begin) <= LIMIT and abs(md.limit_end) <= LIMIT)


def _reference_bad(md: MachineData) -> bool:
    if md.rotary:
        return not md.limit_begin <= md.reference < md.limit_end
    return not md.limit_begin < md.reference < md.limit_end


def _limit_inputs_bad(md: MachineData, levels: tuple[bool, bool]) -> bool:
    if md.limit_polarity not in (0, 1):
        return True
    return any(level if md.limit_polarity == 0 else not level for level in levels)  # actuated now


def _tool_bad(md: MachineData) -> bool:
    if md.rotary:
        return abs(md.tool_length) >= md.limit_end - md.limit_begin
    return (abs(md.tool_length) > LIMIT or md.limit_end + md.tool_length > LIMIT
            or md.limit_begin + md.tool_length < -LIMIT)


def _zero_offsets_bad(md: MachineData) -> bool:
    return any(abs(z) > LIMIT or abs(md.limit_begin - z) > LIMIT or abs(md.limit_end - z) > LIMIT
               for z in md.zero_offsets)


Check = Callable[[MachineData, int, tuple[bool, bool], bool], bool]


def _check(number: int, failing: Check) -> Command[Check]:
    return Command(str(number), failing, "§7.2.1", MD_ERRORS[number])


#: The checks by the machine-data error they give (manual §7.2.1, spec §4.4): True when failing.
CHECKS: Table[Check] = Table([
    _check(12, lambda md, sys, lv, rt: md.module != sys),
    _check(11, lambda md, sys, lv, rt: md.unit not in (1, 2, 3)),
    _check(3, lambda md, sys, lv, rt: not 40 <= md.f_max <= 100_000),
    _check(22, lambda md, sys, lv, rt: not 1 <= md.f_ss <= 10_000 or md.f_ss >= md.f_max),
    _check(6, lambda md, sys, lv, rt: _tau_bad(md)),
    # (the pulse "kleiner der halben Periodendauer" of f_max: t_p < 500 000 µs·Hz / f_max, strictly)
    _check(2, lambda md, sys, lv, rt: not 1 <= md.pulse_us <= 31 or md.pulse_us * md.f_max >= 500_000),
    _check(18, lambda md, sys, lv, rt: md.pulse_polarity not in (0x00, 0x40)),
    _check(5, lambda md, sys, lv, rt: not 12 <= md.pulses_per_rev <= 1000),
    _check(10, lambda md, sys, lv, rt: not 4 <= md.patterns <= 40 or md.pulses_per_rev % md.patterns != 0),
    _check(9, lambda md, sys, lv, rt: not 12 <= md.gear <= 400_000 or md.resolution < 1),
    _check(4, lambda md, sys, lv, rt: any(_velocity_bad(md, v) for v in (md.jog1, md.jog2, md.step_velocity))),
    _check(17, lambda md, sys, lv, rt: (not 1 <= md.reference_velocity <= 65_000
                                        or not md.f_ss < md.frequency(md.reference_velocity) <= md.f_max)),
    _check(15, lambda md, sys, lv, rt: md.reference_direction not in (0x00, 0x20) or md.reference_sync not in (0, 1)),
    _check(7, lambda md, sys, lv, rt: _limits_bad(md)),
    _check(8, lambda md, sys, lv, rt: _reference_bad(md)),
    _check(19, lambda md, sys, lv, rt: _limit_inputs_bad(md, lv)),
    _check(14, lambda md, sys, lv, rt: _tool_bad(md)),
    _check(20, lambda md, sys, lv, rt: not 0 <= md.backlash <= 64_999),
    _check(13, lambda md, sys, lv, rt: _zero_offsets_bad(md)),
    _check(16, lambda md, sys, lv, rt: rt),
])


def stored(words: object, *, axis: int, sys_module: int) -> MachineData:
    """The machine data of a record battery RAM holds for ``axis``: what BA20 stores there, 70
    words of 16 bits with the items as :func:`encode` writes them, the reserve as the host wrote
    it and an MD error the checks give (0 only when they pass with the limit inputs not actuated);
    ValueError for anything else (a hand-edited or damaged state file)."""
    if type(words) is not list or not all(type(w) is int and 0 <= w <= 0xFFFF for w in words):
        raise ValueError(f"the machine data of axis {axis} are no record of 16-bit words")
    md = decode(words)
    if md.axis != axis or encode(md)[:RESERVED.start] != words[:RESERVED.start]:
        raise ValueError(f"the machine data of axis {axis} are no record BA20 stores for it")
    released = (md.limit_polarity == 1,) * 2  # (NC contacts at 24 V, NO contacts open)
    if md.error not in (0, *CHECK_ORDER, 21) or (md.error == 0 and check(md, sys_module=sys_module,
                                                                          limit_levels=released)):
        raise ValueError(f"the machine data of axis {axis} hold MD error {md.error}, which their checks do not give")
    return md
