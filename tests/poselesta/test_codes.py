"""The POSELESTA's character and baud-rate codes (devsim.devices.poselesta.codes) against the
manual's rules as oracles, for every value: the ISO code is 7-bit ASCII with an even parity bit in
bit 7 (§2.6.1.2), the ASCII code the same 7 bits with bit 7 = 0; P68/P70 0 … 5 are 110 … 4800 baud,
4 and 5 on POS III only (§2.6.2.3, §2.6.3)."""

from __future__ import annotations

import hypothesis.strategies as hs
import pytest
from hypothesis import given

from devsim.devices.poselesta import codes


def _ones(value: int) -> int:
    return sum(value >> bit & 1 for bit in range(8))


@pytest.mark.manual("§2.6.1.2", 'Der ISO-Code entspricht dem ASCII-Code mit einem "even parity bit"')
def test_the_iso_byte_of_every_code_has_even_parity() -> None:
    for code in range(256):
        byte = codes.iso_byte(code)
        assert byte & 0x7F == code & 0x7F  # the seven bits, whatever bit 7 was given
        assert _ones(byte) % 2 == 0 and (byte >> 7) == _ones(code & 0x7F) % 2
        assert codes.parity_ok(byte)
        assert codes.parity_ok(code) == (_ones(code) % 2 == 0)


def test_the_tape_image_examples() -> None:
    assert [codes.iso_byte(ord(c)) for c in "%\r\n\x7f"] == [0xA5, 0x8D, 0x0A, 0xFF]
    assert codes.encode("%\r\nN10\x7f", iso=True) == bytes.fromhex("a5 8d 0a 4e b1 30 ff")
    assert codes.encode("%\r\nN10\x7f", iso=False) == b"%\r\nN10\x7f"


@given(hs.text(alphabet=hs.characters(max_codepoint=127), max_size=30), hs.booleans())
def test_encode_is_the_code_of_each_character(text: str, iso: bool) -> None:
    expected = bytes(codes.iso_byte(ord(c)) if iso else ord(c) for c in text)
    assert codes.encode(text, iso) == expected


def test_a_character_beyond_7_bits_cannot_be_sent() -> None:
    with pytest.raises(UnicodeEncodeError):
        codes.encode("ä", iso=True)


@pytest.mark.manual("§2.6.2.3", "Baud-Rate: mit Parameter P 68 wählbar, 0 = 110 ... 5 = 4800 Baud, 4 und 5 nur bei POS III")
def test_the_baud_rate_codes() -> None:
    table = {0: 110, 1: 300, 2: 600, 3: 1200, 4: 2400, 5: 4800}
    for code in (-1, *table, 6, 99):
        assert codes.baud_for_code(code, "III") == table.get(code)
        assert codes.baud_for_code(code, "II") == (None if code in (4, 5) else table.get(code))
