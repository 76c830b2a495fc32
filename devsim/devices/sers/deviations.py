"""Where the sers simulator knowingly differs from its manual, and why (``devsim doc sers``
prints these rows as the *Deviations* section of docs/devices/sers.md)."""

from __future__ import annotations

from devsim.core.kit import Deviation

DEVIATIONS: tuple[Deviation, ...] = (
    Deviation(
        "§2.1.4",
        "below U_W the message 'Vorwarnung Unterspannung' is sent, below U_B the message 'Fehler "
        "Unterspannung'",
        "no unsolicited text is sent for a fault; the host sees P12 value 4 / P11 value 512, the "
        "acknowledgement digit (ok2/ok3/ok4) and the display ('9' blinking / '9')",
        "the manual gives neither the text nor when it would be sent on the line; the spec decides "
        "G-FAULTMSG (no text), so a host parser is never surprised mid-answer; "
        "spontaneous_fault_messages: true sends '*<text>' between lines as the bit gets set",
    ),
    Deviation(
        "§2.1.4",
        "below U_W 'Bit 15 von P12' is set",
        "P12 value 4 ('Warnung Unterspannung') is set, as the P12 list of §4.8.3.1 assigns it",
        "the manual contradicts itself; §4.8.3.1 is the table a host decodes P12 with, and bit 15 "
        "appears nowhere else",
    ),
    Deviation(
        "§2.1.2, §2.1.3, §3.3.1, §3.4",
        "electrical data: opto inputs 13-30 VDC with thresholds 13.5 V (PLC), 3.5 V (TTL), 1 V "
        "(low-active); P-FET outputs fed with 5-30 VDC; ready relay 50 VDC / 100 mA; 5 VDC and 9 VDC "
        "supply pins; shielded encoder cable; RS422 encoder receiver with filters",
        "inputs, outputs and the relay are logical signals (input.*, output.*, output.READY); "
        "the DIP input level only decides which logical level is active",
        "a software twin has no voltages, currents or cables; what a host can observe is the "
        "logical state, which is simulated",
    ),
    Deviation(
        "§4.6.1",
        "at most 64 IF ... THEN ... ELSE ... END structures may be in one program",
        "more are stored and run",
        "the manual names no error message for a 65th structure; refusing it with a guessed errno "
        "would mislead a host more than accepting it",
    ),
    Deviation(
        "§3.2.1, §4.8.6.9",
        "P1017=0: V24 hardware handshake on HSI/HSO (pins 7 and 8 must be wired)",
        "P1017=0 echoes every character like P1017=1; there is no handshake line",
        "a pty and a TCP socket carry no RTS/CTS lines; the echo, which the host sees, is simulated",
    ),
    Deviation(
        "§3.2.1",
        "8 data bits, 1 stop bit, no parity at the baud rate of DIP switch 1",
        "bytes pass unchanged; only the baud rate is compared with the host's (a mismatch garbles "
        "the bytes and shows in line.mismatch)",
        "a pty carries bytes, not a bit stream with framing; data bits, stop bits and parity cannot "
        "differ on it",
    ),
    Deviation(
        "§3.4",
        "I3/I4 count encoder or clock signals up to 100 kHz (4-fold evaluation, direction detection)",
        "pulses arrive as signed counts (encoder.pulses) already evaluated; no frequency limit; with "
        "pulse and direction at I3/I4 (P1053=2, P1143=2) input.I4 active turns the counts negative, at "
        "ENC (P1053=6) the count's sign is the direction",
        "the simulator does not model the edge stream of a pulse input, only its counts",
    ),
    Deviation(
        "§2.1.2, §4.8.1.1",
        "P1038=2 inverts the limit and STOP inputs (open = not reached), for machines without those "
        "switches; an unconnected limit switch reports 'Lagegrenzwertüberschreitung'",
        "P1038 is stored only; input.limit_left/right and input.stop mean 'switch actuated' "
        "whatever P1038 is",
        "the simulated inputs are the logical switch states, not the wiring; P1038 only changes "
        "which voltage means 'actuated', which the twin does not have",
    ),
    Deviation(
        "§4.8.4.5",
        "P147 bit 4 inverts the reference input (NC contact: no signal = the drive stands on the "
        "reference switch)",
        "input.reference means 'the drive stands on the reference switch' whatever bit 4 is; bit 4 "
        "inverts only a digital input chosen as the reference input with P1130 (input.I1..I8 are "
        "the inputs' signals)",
        "as for P1038: the simulated reference input is the switch's logical state (the axis "
        "geometry's cam sets it), not the wiring",
    ),
    Deviation(
        "§4.8.6.6",
        "hand-wheel / electric shaft (P1053=3/7): after a limit switch error the motor is energised "
        "again automatically by pulses in the other direction (P1094 0: at once, 1: once a counter "
        "of the blocked pulses is back at 0); P1147 third pulse counter; P1149 software limits and "
        "compare positions at P1053=7",
        "P1094, P1147, P1149 are stored only; after a limit error the motor stays off until ON "
        "(P11=0 first), pulses toward the blocked side are ignored",
        "the electric shaft with P1053=7 is simulated only as far as the pulse counters and the "
        "following motion; these refinements are not",
    ),
    Deviation(
        "§4.8.4.2",
        "P1140 bit 0: with P1138 != 0 a motor pushed out of place at standstill is corrected by an "
        "automatic POSR",
        "no automatic POSR at standstill",
        "the twin's rotor can be blocked (quantity.stall) but not pushed at standstill, so there "
        "is nothing to correct",
    ),
    Deviation(
        "§4.8.6.7",
        "SERVO mode: P1153 corrects the load angle at speed; with P1152=1 POS=1 once the motor is "
        "inside the window P1161; P1158 deviation from the set profile; P51 follows the encoder "
        "also when an external torque turns the shaft at standstill; a sequence program runs about "
        "43 % slower",
        "P1153 and P1161 are stored only (POS=1 when the motion ends); P1158 reads 0, also while "
        "the load holds the rotor (quantity.stall); the shaft cannot be turned at standstill; "
        "programs run at the normal cycle",
        "the twin's rotor follows the set profile exactly unless stalled, so its deviation from it "
        "is 0; there is no load-angle dynamics for these to act on (P1156, the mean acceleration "
        "of the last ramp, is the set profile's)",
    ),
    Deviation(
        "§4.8.6.1",
        "P1009 commutation table (sine, 87, characteristic 3/4, half/full step), P1159 current "
        "regulator switch speed",
        "stored only; the phase current point shows the commanded amplitude (P1010, P1011)",
        "the twin has no current waveform for these to shape; a host sees them only as stored values",
    ),
    Deviation(
        "§4.6.11, §4.8.6.15",
        "the SERS-Programmer (hand-held terminal) shows texts, asks for the password P1059 and shows "
        "only the parameters and program parts released in P1060-P1073",
        "texts are stored and listed; password and masks are stored only; no Programmer is simulated",
        "the Programmer is a separate device with its own protocol; the serial host is not limited "
        "by the masks",
    ),
    Deviation(
        "§4.8.6.16, §4.8.6.17",
        "CANopen (P1150) and Profibus-DP (P1142) parameters",
        "stored only; the simulated SERS has its RS232/RS485 port only",
        "the fieldbus variants are other products; P1099/P1097 opcodes documented in §4.8.6.16 "
        "are simulated over RS232",
    ),
    Deviation(
        "§4.8.3.1",
        "the list of error numbers: 6-8 (EEPROM chip faults), 14, 18, 20, 26, 27, 29, 31-33, 35, "
        "36, 38-43, 45, 47, 50-53, 55-60, 63, 109-117 (what the keyword reader expected), 17 'Text zu "
        "lang', 46 (the second 'Programmiermodus nicht aktiv'), 62 'Komma nicht erlaubt', 74, 76 "
        "(stored opcodes), 84 'Die Wegdifferenz ist zu groß', 94 (solder bridge), 96/97 (exponent), "
        "100/101 (too large/small to display), 103/104 and P11 4096 (fieldbus), 125 "
        "'Schrittwinkelfehler'",
        "never sent: an unknown or cut keyword is errno 21 'Anweisung erwartet', a text is bounded "
        "by the 60-character line (124), a refused W change is 81/85/86/87, a step loss is P11/P12 "
        "value 32",
        "the manual lists only the texts; it names no input or situation that gives these, and the "
        "statement language has no exponent, no opcodes a host could store and no value X or a "
        "parameter could hold that is not displayable; a guessed trigger would mislead a host more "
        "than the documented errno it gets instead",
    ),
)
