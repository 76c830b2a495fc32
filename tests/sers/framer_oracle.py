"""The SERS line framing of manual §4.1/§4.2, written from the manual as a small oracle: what each
byte of a stream means, to compare the codec with (tests/sers/test_fuzz.py,
tests/sers/test_codec_boundaries.py).  It shares nothing with ``devsim.devices.sers.codec`` but
the event classes.

* Noise before ``#`` is ignored; a CR or LF right after the other one ending a line (or after a
  pair's first half outside a line) is the second half of a pair (``Ignored(pair=True)``).
* ``#`` starts a line (or restarts inside one); the ASCII digits right after it, or one ``*``,
  are the address, announced when the first other byte comes.
* CR or LF ends the line.
* Every character counts toward the 60 of a line (``#``, address, text; a restart goes on
  counting); a text character beyond the 60th is dropped and the line end reports it.
"""

from __future__ import annotations

from devsim.devices.sers.codec import Address, AddressChar, Ignored, LineEnd, Restart, TextChar

LIMIT = 60  # characters per line (§4.1)


def _address(digits: str) -> Address:
    return Address(None if digits == "" else digits if digits == "*" else int(digits))


def framer_events(data: bytes) -> list[list[object]]:
    """The events of each byte of ``data``, fed to a new framer."""
    out: list[list[object]] = []
    in_line, count, dropped, address, last_end = False, 0, False, None, None
    for byte in data:
        events: list[object] = []
        out.append(events)
        end_before, last_end = last_end, None
        if byte in b"\r\n":
            if not in_line:
                events.append(Ignored(pair=end_before is not None and end_before != byte))
                continue
            if address is not None:
                events.append(_address(address))
            events.append(LineEnd(dropped))
            in_line, address, last_end = False, None, byte
            continue
        if byte == ord("#"):
            events.append(Restart(mid_line=in_line))
            if not in_line:
                count, dropped = 0, False
            in_line, address, count = True, "", count + 1
            continue
        if not in_line:
            events.append(Ignored())
            continue
        count += 1
        char = chr(byte)
        if address is not None:
            if (char in "0123456789" and address != "*") or (char == "*" and address == ""):
                address += char
                events.append(AddressChar())
                continue
            events.append(_address(address))
            address = None
        dropped = dropped or count > LIMIT
        events.append(TextChar(char, dropped=count > LIMIT))
    return out


def line_state(data: bytes) -> tuple[bool, int]:
    """After ``data``: whether a line is open, and how many characters it has (§4.1's count)."""
    in_line, count = False, 0
    for byte in data:
        if byte in b"\r\n":
            in_line = False
        elif byte == ord("#"):
            count = count + 1 if in_line else 1
            in_line = True
        elif in_line:
            count += 1
    return in_line, count if in_line else 0
