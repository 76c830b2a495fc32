"""Machine words as the controllers' records and registers carry them: 32-bit two's complement."""

from __future__ import annotations

__all__ = ["signed32"]


def signed32(value: int) -> int:
    """The signed value of the low 32 bits of ``value``."""
    value &= 0xFFFF_FFFF
    return value - (1 << 32) if value & 0x8000_0000 else value
