"""Where the gms96 simulator knowingly differs from its manual, and why (``devsim doc gms96``
prints these rows as the *Deviations* section of docs/devices/gms96.md)."""

from __future__ import annotations

from devsim.core.kit import Deviation

DEVIATIONS: tuple[Deviation, ...] = (
    Deviation(
        "§2.1",
        "RS422 four-wire line used half duplex, DIN 19244 at 9600 or 38400 Bd, 8 data bits, even parity, 1 stop bit",
        "the line is a pty or a socket: bytes arrive whole, without RS422 levels; a pty shows the host's baud rate "
        "and stop bits but not its parity or data bits, RFC 2217 shows them all, and a host set otherwise than the "
        "card gets the bytes garbled as a UART would (silence, as for a parity error)",
        "a pty carries bytes, not bits or line levels",
    ),
    Deviation(
        "§2.2",
        "switches 1..4 select the address with on/on/on/on = 0 ... off/off/off/off = 15, switch 5 on adds 16",
        "the configuration gives the switches' meaning: dil.address 0..31, interpolation, protocol S|E, baud",
        "the meaning is what a host sees; the on/off inversion of real switches has no observable effect",
    ),
    Deviation(
        "§1.1",
        "the position controller is a digital PIDT1 loop sampled every 1 ms (P N10, D N11, T1 N12, I N13; "
        "N25 I part during moves, N26 500 us sampling)",
        "the actual position follows the set-point as a first-order lag with Kv = 0.2·N10 (following error "
        "v/Kv, closed form); N11, N12, N13, N25 and N26 are stored and read back with T5, they shape nothing",
        "the twin serves host software: it needs the following error's size and the N20 fault, not a tuned loop",
    ),
    Deviation(
        "§1.2",
        "a digital PI current controller sampled every 128 us (§6: 125 us), P N34, I N35",
        "the motor current is a model of the load (T1;5, H7, I²t); N34 and N35 are stored with their coupling "
        "rule and read back, no current loop runs",
        "electrical dynamics below the millisecond are not observable by a host",
    ),
    Deviation(
        "§1.4",
        "the PLC runs a Step5 program (downloaded with p1;100, a frames, p1;101) with timers, counters, data "
        "words; a debugger shows RLO, inputs, outputs and markers",
        "the downloaded frames are stored opaquely (T3;4 and persistence behave as on the card) and a scripted "
        "PLC (config plc: rules and a Python hook) runs instead of the Step5 code",
        "the Step5 instruction set of the GMS PLC is documented separately, not in this manual",
    ),
    Deviation(
        "§2.4.4",
        "axis protection functions (FB 254, function 27) block moves while PLC conditions stand",
        "not simulated; FB 254 exists only as fb254(22, ...) for scripted hooks (H22 data); a blocked axis is "
        "the machine-side blocked_axis fault",
        "FB 254 is described in the separate Step5 documentation",
    ),
    Deviation(
        "§2.3.1 N",
        "N8 (home-position window, FB 254/12), N16 (resolver pole count), N32 (position monitoring), N45 (field "
        "symmetry / GD96 top speed), N50 bit 0 (counter input as actual value), N52/N53 (SPA/SPE cards on the "
        "auxiliary interface), N43, N44, N54, N55, N56 (reserved)",
        "stored, clamped to their ranges and read back with T5; they change no behaviour",
        "they act on hardware the twin does not have (resolver, auxiliary interface) or through FB 254",
    ),
    Deviation(
        "§2.3.1 N",
        "N22 = 1 inverts the motor's direction of rotation",
        "only the spindle simulation (Q8) turns the other way; positioning moves, cam and limit switches keep "
        "the set-point's direction",
        "the axis model has one coordinate for set-point, actual value and switches; mirroring it is not done yet",
    ),
    Deviation(
        "§2.3.1 p",
        "p3: P3 is the program number 0..31",
        "programs 0..99 are accepted (config max_programs, default 100)",
        "§1.5 and §2.5 of the same manual allow 100 CNC programs; the larger number is taken",
    ),
    Deviation(
        "§2.3.1 q",
        "q also makes the card report its internal fault states (e.g. lost contact to power stages) again",
        "q sets M3.1 for the PLC; the card has no internal fault messages of its own to repeat",
        "the faults named are those of multi-stage hardware the twin does not model",
    ),
    Deviation(
        "§2.4.1",
        "M3.7: the static data DW0..39 are saved when a monitoring situation occurs",
        "DW0..DW79 (and MB18) are saved whenever they change by d/c and when the power goes off, whatever M3.7 is",
        "the twin's non-volatile memory does not lose data on a power failure",
    ),
    Deviation(
        "§3.1",
        "at a 100 % excess of the I²t limit 2 s are allowed (formerly 0.2 s); the example says 0.2 s",
        "2 s by default; config axis.i2t_t_allow_s sets another time (0.2 for the older software)",
        "the manual contradicts itself; the statement for the current software is taken",
    ),
    Deviation(
        "§3.1",
        "KD/HD cards: programmable voltage and temperature thresholds; DC-bus voltage and heat-sink temperature "
        "can be read over the interface",
        "thresholds are not programmable and no such read-back exists; monitoring causes are injected (quantity."
        "monitoring, the monitoring fault)",
        "the command for it is not documented in this manual",
    ),
    Deviation(
        "§4.2",
        "each output may deliver 500 mA, 2 A in total; at about 2.5 A all outputs switch off until the 24 V "
        "supply has been off for at least 10 s",
        "currents are not modelled: the machine side sets output_overload; all outputs go off and E2.2 shows it "
        "until the next power-on of the card (with the overload gone)",
        "there is no separate 24 V supply in the twin; its power-on stands for switching the 24 V off and on",
    ),
    Deviation(
        "§4.4",
        "behind a GMS-I interpolation card each GMS shows 16 bits in the PAE/PAA of the interpolation card and "
        "communicates through it",
        "DIL 6 (interpolation) removes the PLC and ORs E1.6/E1.7 with E2.0/E2.1; the GMS-I card itself is not "
        "simulated",
        "the interpolation card is a device of its own",
    ),
    Deviation(
        "§6",
        "electrical data per type: voltages, currents, ballast, capacitors, efficiency, resolver excitation, "
        "encoder line frequency, clock of the power stage",
        "kept as the variant table (devsim doc gms96) and used for the LED/monitoring model; nothing electrical "
        "is simulated",
        "a pty carries no power",
    ),
)
