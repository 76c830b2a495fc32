"""POSELESTA character codes, baud-rate codes and keyboard codes (manual §2.6.1.2, §2.6.2.3,
§2.6.3, §2.6.4; spec poselesta.md §2.3, §2.4, §3.10, §6.1).

Pure functions, no I/O.  ISO code is 7-bit ASCII with an *even* parity bit; on a pty (8-bit
bytes) the parity travels in bit 7, the classic 8-track tape image: ``%`` → ``A5``, CR → ``8D``,
LF → ``0A``, DEL → ``FF``.  ASCII code is the same 7 bits with bit 7 = 0.
"""

from __future__ import annotations

__all__ = [
    "BAUD_CODES",
    "KEY_CODES",
    "POS3_ONLY_BAUD_CODES",
    "WERTBEREICHES_UEBERLAUF",
    "baud_for_code",
    "encode",
    "iso_byte",
    "parity_ok",
]

#: The only error message the manual gives for serial input ("value range overflow", §2.6).
WERTBEREICHES_UEBERLAUF = "WERTBEREICHES-UEBERLAUF"

#: P68 (V6) and P70 (V7): code → baud (§2.6.2.3, §2.6.3); 4 and 5 on POS III only.
BAUD_CODES = {0: 110, 1: 300, 2: 600, 3: 1200, 4: 2400, 5: 4800}
POS3_ONLY_BAUD_CODES = frozenset({4, 5})

#: The 45 key codes of the external keyboard (§2.6.4; key "P" = 48h).
KEY_CODES = frozenset(
    bytes.fromhex(
        "020304 07080D0E0F 161718191A1B1C 1E1F2122232425262A2C2D2E2F 3234363738393E404243444648"
        "4A4C4D4E".replace(" ", "")
    )
)


def baud_for_code(code: int, variant: str) -> int | None:
    """The baud rate of a P68/P70 code, or None where the variant does not have it."""
    if code in POS3_ONLY_BAUD_CODES and variant != "III":
        return None
    return BAUD_CODES.get(code)


def iso_byte(code: int) -> int:
    """The ISO byte of a 7-bit code: bit 7 makes the number of 1-bits even."""
    code &= 0x7F
    return code | 0x80 if bin(code).count("1") & 1 else code


def parity_ok(byte: int) -> bool:
    """Whether an ISO byte has even parity over all 8 bits."""
    return bin(byte).count("1") % 2 == 0


_ISO = bytes(iso_byte(c) for c in range(128))


def encode(text: str, iso: bool) -> bytes:
    """``text`` (7-bit characters) as the bytes on the line: with the ISO parity bit or plain."""
    data = text.encode("ascii")
    return data.translate(_ISO_TABLE) if iso else data


_ISO_TABLE = _ISO + bytes(range(128, 256))
