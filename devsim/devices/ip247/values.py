"""How the IP247 encodes values and small records (manual §2.5.4.6, §6.2.7.2, §6.2.9.3,
§6.3.8.3–§6.3.8.7; spec ip247.md §3.3.2, §3.4.3–§3.4.7).

Values from the PLC are binary or BCD as the axis's machine data say ("AG BCD-codiert"): a path
is a signed 32-bit number, or 7 BCD decades with the sign in bits 31…28; a velocity a word, or 4
BCD decades with the byte parameter 1 meaning ×10.  Values to the PLC are BCD when asked and
representable, else binary (flagged).  Pure functions; :class:`NotBcd` carries the module error
(66 path, 67 velocity).
"""

from __future__ import annotations

from devsim.core.words import signed32

__all__ = [
    "NotBcd", "actual_values", "md_directory", "md_overview", "path_from_plc", "path_to_plc", "program_directory",
    "sys_id_record", "velocity_from_plc",
]

BCD_LIMIT = 9_999_999


class NotBcd(ValueError):
    """A PLC value that should be BCD is not: module error 66 (path) or 67 (velocity)."""

    def __init__(self, error: int) -> None:
        super().__init__(f"module error {error}: value not BCD-coded")
        self.error = error


def _bcd_digits(value: int, digits: int, error: int) -> int:
    result = 0
    for shift in range(digits - 1, -1, -1):
        nibble = value >> (4 * shift) & 0xF
        if nibble > 9:
            raise NotBcd(error)
        result = result * 10 + nibble
    return result


def _to_bcd(value: int, digits: int) -> int:
    result = 0
    for shift in range(digits):
        result |= (value // 10**shift % 10) << (4 * shift)
    return result


def path_from_plc(raw: int, bcd: bool) -> int:
    """A double-word parameter (path, target, offset) in base units (spec §3.3.2)."""
    raw &= 0xFFFF_FFFF
    if not bcd:
        return signed32(raw)
    sign = raw >> 28
    if sign not in (0x0, 0xF):
        raise NotBcd(66)
    value = _bcd_digits(raw & 0x0FFF_FFFF, 7, 66)
    return -value if sign == 0xF else value


def velocity_from_plc(word: int, byte: int, bcd: bool) -> int:
    """A velocity parameter in unit/min: the word, or 4 BCD decades × 10 when the byte is 1."""
    if not bcd:
        return word & 0xFFFF
    value = _bcd_digits(word & 0xFFFF, 4, 67)
    return value * 10 if byte == 1 else value


def path_to_plc(value: int, bcd: bool) -> tuple[int, bool]:
    """A value for the PLC (ANZG, BA66): ``(raw 32-bit, binary_instead)`` — BCD with the sign
    nibble when asked and |value| ≤ 9 999 999, else two's-complement binary."""
    if bcd and abs(value) <= BCD_LIMIT:
        return (0xF000_0000 if value < 0 else 0) | _to_bcd(abs(value), 7), False
    return value & 0xFFFF_FFFF, bcd


def _dd(value: int) -> tuple[int, int]:
    value &= 0xFFFF_FFFF
    return value >> 16, value & 0xFFFF


def sys_id_record(module: int, slot: int, page: int, firmware: str = "A02.1", module_type: str = "IP247 ") -> list[int]:
    """BA70: 9 words — type (6 characters), firmware (6), module, slot, page (spec §3.4.3)."""
    text = (module_type.ljust(6)[:6] + firmware.ljust(6)[:6]).encode("latin-1")
    return [text[i] << 8 | text[i + 1] for i in range(0, 12, 2)] + [module & 0xFF, slot & 0xFF, page & 0xFF]


def md_directory(axes: list[tuple[int, int] | None]) -> list[int]:
    """BA64: per axis the DB number and the length in words (70), 0 0 without MD (§3.4.4)."""
    words: list[int] = []
    for entry in axes:
        words += list(entry) if entry is not None else [0, 0]
    return words


def program_directory(programs: list[tuple[int, int]]) -> list[int]:
    """BA65: per program, in storage order, its number and record length in words (§3.4.5)."""
    return [word for number, length in programs for word in (number, length)]


def actual_values(position: int, residual: int, bcd: bool = False) -> tuple[list[int], int]:
    """BA66: position, 2 unused words, residual (§3.4.6); with ``bcd`` each as BCD where it can
    be (the flags: bit 0 position, bit 1 residual stayed binary, FB165 MB249)."""
    pos, pos_binary = path_to_plc(position, bcd)
    res, res_binary = path_to_plc(residual, bcd)
    return [*_dd(pos), 0, 0, *_dd(res)], int(pos_binary) | int(res_binary) << 1


def md_overview(axes: list[tuple[int, int, int, int, int] | None]) -> list[int]:
    """BA68: per axis DB number, module, axis, length, MD error; zeros without MD (§3.4.7)."""
    words: list[int] = []
    for entry in axes:
        words += list(entry) if entry is not None else [0] * 5
    return words
