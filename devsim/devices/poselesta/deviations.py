"""Where the poselesta simulator knowingly differs from its manual, and why (``devsim doc poselesta``
prints these rows as the *Deviations* section of docs/devices/poselesta.md)."""

from __future__ import annotations

from devsim.core.kit import Deviation

DEVIATIONS: tuple[Deviation, ...] = (
    Deviation(
        "§2.6.1.2",
        "ISO code is sxxxxxxxPSS (7 data bits, even parity, 2 stop bits), ASCII sxxxxxxxSS, the printer "
        "sxxxxxxxOSS or sxxxxxxxOPSS (an eighth data bit 0, then the parity bit)",
        "every port reports 8 data bits, no parity, 2 stop bits (8N2) to the line: ISO's parity bit travels as "
        "bit 7 of the byte, ASCII and the printer send bit 7 = 0 and the printer's parity bit is not sent; the "
        "control times its output with the manual's frame (ISO 11, ASCII 10, printer 12 or 11 bits a character)",
        "a pty carries 8-bit bytes and no parity bit; 8N2 keeps every host that opens the port as the "
        "manual's examples do matching the device",
    ),
    Deviation(
        "§2.6",
        "a wrong baud rate or code before a read-in gives WERTBEREICHES-UEBERLAUF; a real UART sees framing "
        "errors at a wrong baud rate",
        "before % the read-in ends with WERTBEREICHES-UEBERLAUF at the first byte that no sender with the "
        "control's settings sends: ISO a parity error; ASCII a byte with bit 7 set and odd parity, or a control "
        "character other than NUL, LF, CR (DEL and all printable characters are ignored, as §2.6.3 says)",
        "the pty delivers what a UART samples but no framing-error flag; these bytes are what a garbled line "
        "delivers in their place",
    ),
    Deviation(
        "§2.6.1.1",
        "V.24 levels (±3 … 15 V) or a 20 mA current loop (V7 only by current loop), cable lengths, potential "
        "separation by opto-couplers",
        "bytes on a pty or a TCP socket",
        "electrical properties a byte stream does not have",
    ),
)
