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
        "control's settings sends: ISO a parity error; ASCII a byte with bit 7 set and odd parity (every 7-bit "
        "character, control characters such as a DNC host's DC2 and DC4 included, is ignored, as §2.6.3 says); after % "
        "an ASCII port stops as well at a byte with bit 7 set and odd parity (an ISO image's bit 7 is masked)",
        "the pty delivers what a UART samples but no framing-error flag; these bytes are what a garbled line "
        "delivers in their place",
    ),
    Deviation(
        "§2.6.4",
        "'Ueber die Eingangsklemme V21/9 kann in jeder Betriebsart von der internen auf die externe Tastatur "
        "umgeschaltet werden': one keyboard at a time",
        "[SIM-CHOICE] panel.key (the front-panel keyboard) is accepted whichever keyboard V21/9 selects; V8 keys "
        "count only while V21/9 selects the external keyboard",
        "panel.key is the control API's operator at whichever keyboard is in use (there is no separate key "
        "point for the external one); the manual's §2.3.11 on V21/9 is lost",
    ),
    Deviation(
        "§2.6.1.1",
        "V.24 levels (±3 … 15 V) or a 20 mA current loop (V7 only by current loop), cable lengths, potential "
        "separation by opto-couplers",
        "bytes on a pty or a TCP socket",
        "electrical properties a byte stream does not have",
    ),
    Deviation(
        "§2.2",
        "the encoders V1–V4 deliver sine or TTL signals (A, B, reference mark of 90 … 270° width, +5 V supply of "
        "at most 200 mA, interpolation inside the control)",
        "the actual value is computed from the axis model; of the encoders only the reference marks (positions "
        "in config axes.<a>.reference_marks), the highest input frequency (encoder_khz) and the faults "
        "encoder_loss_<a>, count_loss_<a>, rm_missing_<a> are simulated",
        "signal shapes, levels and supply currents are electrical; the host and the PLC see their effect only",
    ),
    Deviation(
        "§2.3, §2.4",
        "inputs H = 18 … 40 V, L = 0 … 3 V or open, 3 … 8 mA; outputs 24 V, 100 mA, short-circuit proof; the "
        "set-points ±10 V into at least 5 kΩ; the pots on V23 fed with +10 V",
        "an input or output is a level (True = H), a set-point or a pot a number of volts",
        "electrical properties a simulated level does not have",
    ),
    Deviation(
        "§2.3.14",
        "P1 selects mm or inch for the machine parameter and tool catalogues (the table's rows 3 and 4: "
        "catalogues in inch); after changing P1 the catalogue must be entered again",
        "P1 is stored and read back but has no effect: the catalogues are always in mm; V22/2 (inch "
        "programming and display) acts as the manual's rows 1 and 2 say",
        "the inch catalogue's scaling of every parameter is not described in the manual (spec §4.8: stored only)",
    ),
    Deviation(
        "§2.7, §2.3.25, §2.3.1",
        "the control shows its state on a 12-inch screen over composite video (V9): messages, the diagnostic "
        "pages, the function keys of NC-Stop and NC-Start, the start/stop symbol",
        "the screen is not drawn: what it shows is read as points (panel.message, diagnostics.input_screen, "
        "diagnostics.pots, diagnostics.keyboard_test, panel.function_keys, output.start_stop_status)",
        "a video signal is not something a host program reads; the points carry the same information",
    ),
)
