"""SERS parameter rows: inputs/outputs, system and status parameters (manual §4.8.1–§4.8.3)."""

from __future__ import annotations

from devsim.devices.sers.paramdef import POS_MAX as _POS_MAX
from devsim.devices.sers.paramdef import POS_MIN as _POS_MIN
from devsim.devices.sers.paramdef import RW_E as _RW_E
from devsim.devices.sers.paramdef import Rows

__all__ = ["ROWS"]

_p = Rows()

# ============================================================================================
# 4.8.1 Inputs / outputs (§4.8.1)
# ============================================================================================
_p(
    1300,
    "Eingänge",
    "inputs",
    aliases=("IN",),
    minimum=0,
    maximum=255,
    writable=False,
    commands=tuple(f"I{i}" for i in range(1, 9)),
    doc="State of inputs I1..I8, binary (I1=1 ... I8=128); P1300=11 -> I1, I2, I4. "
    "IF syntax also I1..I8 and legacy IN0..IN255.",
)
_p(
    1301,
    "Eingänge I/O-Erweiterung",
    "inputs I/O extension",
    minimum=0,
    maximum=255,
    writable=False,
    commands=tuple(f"I{i}" for i in range(9, 17)),
    doc="Inputs I9..I16 (valid only with option IO).",
)
_p(
    1021,
    "DigIn-Freigabe",
    "digital input enable",
    minimum=0,
    maximum=255,
    **_RW_E,
    doc="Manual functions on the inputs when the service switch is off: 1 I1 left slow; 2 I2 right "
    "slow; 4 I3 left fast; 8 I4 right fast; 16 I5 homing; 32 I6 motor ON/OFF (ON also clears "
    "P11/P12); 64 I7 stop (manual prints 84); 128 I8 start program.",
    attr="input_enable",
)
_p(
    1056,
    "Endschalter und Digin",
    "limit switches and digital inputs",
    writable=False,
    doc="Internal use only.",
)
_p(
    1022,
    "DigIn-Label-Freigabe",
    "digital input label enable",
    minimum=0,
    maximum=255,
    **_RW_E,
    doc="Inputs used as address lines in parallel mode (P1022=15 -> I1..I4); P1021 must contain 128.",
    attr="input_label_enable",
)
_p(
    1098,
    "Freigabe Programmsprung",
    "program jump enable",
    minimum=0,
    maximum=255,
    **_RW_E,
    doc="Event mode: bit n-1 -> rising edge on In jumps to Ln (§4.5.2).",
    attr="program_jump_enable",
)
_p(
    1023,
    "Start-Freigabe",
    "start enable",
    minimum=0,
    maximum=1,
    **_RW_E,
    doc="0 = program start on an edge at I8; 1 = start while I8 is set (level).",
    attr="start_enable",
)
_p(
    1046,
    "Analog-Eingang ADC",
    "analog input ADC",
    aliases=("ADC",),
    kind="fixed",
    decimals=3,
    minimum=0,
    maximum=1,
    writable=False,
    doc="Analog input, 10 bit; re-read on every use. Simulator: fraction 0.000..1.000 of 5 V (G-ADC).",
)
_p(
    1135,
    "ADC-Hysterese",
    "ADC hysteresis",
    minimum=0,
    maximum=255,
    default=7,
    **_RW_E,
    doc="x = 2^n-1 -> hysteresis n bits, resolution 10-n bits (7 = default, 7-bit resolution).",
    attr="adc_hysteresis",
)
_p(
    1148,
    "ADC-Offset",
    "ADC offset",
    minimum=0,
    maximum=255,
    **_RW_E,
    doc="Subtracted from the ADC value, scale 0..255 = 0..5 V.",
    attr="adc_offset",
)
_p(
    1130,
    "Referenz-Schalter Digin Zuweisung",
    "reference switch input assignment",
    minimum=0,
    maximum=8,
    **_RW_E,
    doc="0 = standard reference input; 1..8 = input I1..I8 is the reference switch.",
    attr="reference_input",
)
_p(
    1038,
    "Invertieren End-/Stopschalter",
    "invert limit/stop switches",
    minimum=0,
    maximum=2,
    **_RW_E,
    doc="0 = standard (24 V = not actuated); 1 = test mode (must not be set); 2 = inverted.",
)
for _i in range(1, 17):
    _p(
        1200 + _i,
        f"Ausgang {_i}",
        f"output {_i}",
        aliases=(f"O{_i}",),
        minimum=0,
        maximum=1,
        doc=(
            f"Digital output O{_i}." if _i <= 4 else f"Extension output O{_i} (option IO only, else errno 4)."
        ),
    )
_p(
    1036,
    "Ausgang Bremse",
    "brake output",
    minimum=-4,
    maximum=4,
    **_RW_E,
    doc="On OFF: 1..4 switch O1..O4 on; -1..-4 switch O1..O4 off; 0 = off.",
    attr="brake_output",
)
_p(
    1024,
    "Vergleichsposition 1",
    "compare position 1",
    kind="position",
    minimum=_POS_MIN,
    maximum=_POS_MAX,
    too_large_errno=88,
    too_small_errno=89,
    **_RW_E,
    doc="When P51 = P1024 the action P1025 is executed.",
    attr="compare_position1",
)
_p(
    1025,
    "Vergleichsausgang 1",
    "compare output 1",
    minimum=-7,
    maximum=7,
    **_RW_E,
    doc="0 off; 1..4 set O1..O4; -1..-4 clear; 5..7 set M1..M3; -5..-7 clear M1..M3. "
    "(Manual heading misprinted 'Vergleichsausgang 2', spec §7.3.)",
    attr="compare_output1",
)
_p(
    1026,
    "Vergleichsposition 2",
    "compare position 2",
    kind="position",
    minimum=_POS_MIN,
    maximum=_POS_MAX,
    too_large_errno=90,
    too_small_errno=91,
    **_RW_E,
    doc="As P1024.",
    attr="compare_position2",
)
_p(1027, "Vergleichsausgang 2", "compare output 2", minimum=-7, maximum=7, **_RW_E, doc="As P1025.", attr="compare_output2")
_p(
    1125,
    "Ausgang Motor IN-Position",
    "output motor in position",
    minimum=-4,
    maximum=4,
    **_RW_E,
    doc="1..4: O1..O4 := P336; -1..-4 inverted.",
    attr="output_in_position",
)
_p(
    1126,
    "Ausgang Programm läuft",
    "output program running",
    minimum=-4,
    maximum=4,
    **_RW_E,
    doc="1..4: O1..O4 := 1 while a program runs; -1..-4 inverted.",
    attr="output_program_running",
)
_p(
    1131,
    "Ausgang SERS-Fehler",
    "output SERS error",
    minimum=-4,
    maximum=4,
    **_RW_E,
    doc="1..4: O1..O4 := 1 while P11 != 0; -1..-4 inverted.",
    attr="output_error",
)
_p(
    1132,
    "Ausgang SERS-Warnung",
    "output SERS warning",
    minimum=-4,
    maximum=4,
    **_RW_E,
    doc="1..4: O1..O4 := 1 while P12 != 0; -1..-4 inverted.",
    attr="output_warning",
)
_p(
    1160,
    "Überlast Ausgang",
    "overload output",
    minimum=-8,
    maximum=8,
    **_RW_E,
    doc="SERVO only: 1..4 set O1..O4 latched; -1..-4 clear latched; 5..8 set O1..O4 while the "
    "overload lasts; -5..-8 clear temporarily.",
    attr="overload_output",
)

# ============================================================================================
# 4.8.2 System parameters
# ============================================================================================
_p(
    0,
    "E²PROM Modus",
    "EEPROM mode",
    choices=frozenset({0, 1, 2}),
    invalid_errno=82,
    commands=("QUIT", "RUN", "NEW"),
    doc="0 = not running (writing 0 ends programming mode, QUIT); 1 = run (RUN); 2 = programming "
    "mode with deletion (NEW). PGM = programming mode without deletion.",
)
_p(
    134,
    "Master-Steuerwort",
    "master control word",
    choices=frozenset({0, 7}),
    commands=("ON", "OFF"),
    doc="Motor current: ON = 7, OFF = 0.",
)
_p(
    1134,
    "Drehrichtungsumkehr",
    "direction reversal",
    minimum=0,
    maximum=1,
    **_RW_E,
    doc="1 = motor direction inverted: the same effect as swapping the leads within one motor phase.",
    attr="direction_inverted",
)
_p(
    1136,
    "Erhöhte Chopperfrequenz",
    "increased chopper frequency",
    minimum=0,
    maximum=1,
    **_RW_E,
    doc="12 A versions: 0 = 12 kHz, 1 = 18 kHz. Versions <= 6 A: fixed (write -> errno 105 [SIM]).",
)
_p(
    1133,
    "Firmware-Version",
    "firmware version",
    default=120901,
    writable=False,
    commands=("VER",),
    doc="Read-only; also via VER.",
)

# ============================================================================================
# 4.8.3 Status (§4.5, §4.6)
# ============================================================================================
_p(
    11,
    "Antriebsfehler",
    "drive errors",
    choices=frozenset({0}),
    doc="Error bits: 2 overtemperature, 32 step monitoring, 128 short circuit, 512 undervoltage, "
    "2048 standstill monitoring, 4096 communication, 8192 limit switch. Only 0 may be written.",
)
_p(
    12,
    "Warnungen",
    "warnings",
    choices=frozenset({0}),
    doc="Warning bits: 1 limit, 2 overtemp, 4 undervoltage, 8 internal position limit, 16 error "
    "message, 32 step monitoring, 64 setpoint limit, 128 program error, 256 arithmetic, "
    "1024 RS232 overflow, 2048 SERVO not active. Only 0 may be written.",
)
_p(
    1137,
    "Letzte Fehlermeldungsnummer (errno)",
    "last error message number (errno)",
    writable=False,
    doc="Number of the last error message (§3.6).",
)
_p(
    336,
    "Positionsstatus - In_Position",
    "position status - in position",
    aliases=("POS",),
    minimum=0,
    maximum=1,
    default=1,
    writable=False,
    doc="0 while moving, 1 when standing.",
)
_p(
    1121,
    "Selbstständige Meldung In_Position",
    "spontaneous message in position",
    minimum=0,
    maximum=1,
    **_RW_E,
    doc="1 = send '@nPOS=1' at the end of every positioning.",
    attr="report_in_position",
)
_p(
    1129,
    "Selbstständige Meldung Fertig_Programm",
    "spontaneous message program finished",
    minimum=0,
    maximum=1,
    **_RW_E,
    doc="1 = send '@nP0=0' at the end of a program.",
    attr="report_program_end",
)
_p(
    403,
    "Status Lageistwerte",
    "actual position status",
    default=3,
    writable=False,
    doc="3 after power-on (not homed); 0 after a successful homing run.",
)
_p(
    1015,
    "Beschleunigungsphase",
    "acceleration phase",
    minimum=0,
    maximum=1,
    writable=False,
    doc="1 while accelerating or decelerating.",
)
_p(
    1016,
    "Konstantphase",
    "constant phase",
    minimum=0,
    maximum=1,
    writable=False,
    doc="1 while moving at constant velocity.",
)
_p(
    1013,
    "Treiberstatus und Endschalter",
    "driver status and limit switches",
    minimum=0,
    maximum=65535,
    writable=False,
    commands=("J1", "J2", "J3", "J4", "J5"),
    doc="Bits: 1 limit right open (J3), 2 limit left open (J2), 4 STOP open (J4), 8 reference "
    "open (J1), 128 service switch open (J5). J values are the inverse of these bits.",
)
_p(
    1042,
    "Grenzposition überschritten",
    "limit position exceeded",
    aliases=("LP",),
    minimum=0,
    maximum=1,
    writable=False,
    doc="1 if P51 < P1040 or P51 > P1041.",
)
_p(
    1123,
    "Nächsten Polynomabschnitt laden",
    "load next polynomial segment",
    minimum=0,
    maximum=1,
    writable=False,
    doc="1 = the next polynomial segment is expected.",
)


ROWS = tuple(_p)
