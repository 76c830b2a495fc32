"""SERS parameter rows: programming and other parameters (manual §4.8.5, §4.8.6)."""

from __future__ import annotations

from devsim.devices.sers.paramdef import POS_MAX as _POS_MAX
from devsim.devices.sers.paramdef import POS_MIN as _POS_MIN
from devsim.devices.sers.paramdef import RW_E as _RW_E
from devsim.devices.sers.paramdef import Rows

__all__ = ["ROWS"]

_p = Rows()

# ============================================================================================
# 4.8.5 Programming parameters
# ============================================================================================
_p(
    1100,
    "Zeitverzögerung",
    "time delay",
    aliases=("D",),
    kind="fixed",
    decimals=1,
    minimum=0.1,
    maximum=6553.5,
    readable=False,
    doc="Blocking delay in 0.1 s (D=1 -> 100 ms, D=0.1 -> 10 ms); x1.2 when P1141=0.",
)
_p(
    1141,
    "Zeitverzögerung - Korrektur",
    "time delay correction",
    minimum=0,
    maximum=1,
    **_RW_E,
    doc="0 = V01..V03 delay factor 1.2; 1 = factor 1.0.",
    attr="delay_correction",
)
_p(
    1164,
    "Wartezeit D2",
    "waiting time D2",
    aliases=("D2",),
    kind="fixed",
    decimals=1,
    minimum=0,
    maximum=6553.5,
    doc="Non-blocking timer in 0.1 s; DB := 1 when elapsed.",
    attr="d2_time",
)
_p(
    1165,
    "Wartezeit Bit DB",
    "waiting time bit DB",
    aliases=("DB",),
    minimum=0,
    maximum=1,
    writable=False,
    doc="Set when D2 has elapsed.",
    attr="d2_bit",
)
_p(
    100,
    "Zähler 1",
    "counter 1",
    aliases=("C1",),
    minimum=0,
    maximum=65535,
    mode3_range=(-32768, 32767),  # "vorzeichenbehaftet (-32768 bis 32768)": 16 bits [SIM-CHOICE: 32767]
    doc="Unsigned 16-bit (manual: 0..65536); signed -32768..32767 overflow counter when P1014=3.",
    attr="counter1",
)
_p(
    101,
    "Zähler 2",
    "counter 2",
    aliases=("C2",),
    minimum=0,
    maximum=65535,
    doc="Unsigned 16-bit counter (manual: 0..65536).",
)
_p(
    102,
    "Zähler 3",
    "counter 3",
    aliases=("C3",),
    minimum=0,
    maximum=4294967295,
    doc="Unsigned 32-bit counter.",
)
for _i in (1, 2, 3):
    _p(1100 + _i, f"Merker {_i}", f"flag {_i}", aliases=(f"M{_i}",), minimum=0, maximum=1, doc="Flag.")
_p(
    1028,
    "Listoption",
    "list option",
    minimum=0,
    maximum=31,
    default=1,
    **_RW_E,
    doc="Bits: 1 statement numbers; 2 units; 4 indented; 8 keep user line breaks; 16 LISTP texts.",
    attr="list_option",
)
_p(
    1110,
    "Warten bis fertig positioniert ist",
    "wait until positioned",
    minimum=0,
    maximum=1,
    default=1,
    doc="Master: 1 = wait for own E to finish. Always 1 after power-on, not stored.",
    attr="wait_until_positioned",
)
_p(
    1,
    "Zieladresse",
    "target address",
    aliases=("Z",),
    minimum=0,
    maximum=127,
    doc="Master target address (0 = self); '*' (broadcast) allowed only here (errno 19 elsewhere).",
    attr="target_address",
)
_p(2, "IF Senden/Erhalten", "IF send/receive", doc="Internal: master->slave IF query ('P2=336' = 'IF 336').")
_p(
    3,
    "Slave Parameterabfrage",
    "slave parameter query",
    doc="Internal buffer for master->slave reads ('#1P3=91'). Not in the §4.7 list.",
)

# ============================================================================================
# 4.8.6 Other parameters
# ============================================================================================
_p(
    1009,
    "Kommutierungstabelle",
    "commutation table",
    minimum=0,
    maximum=5,
    default=1,
    **_RW_E,
    doc="0 sine; 1 '87' characteristic; 2 characteristic 3 (sine²); 3 characteristic 4; "
    "4 half step; 5 full step.",
)
_p(
    1010,
    "Phasenstrom",
    "phase current",
    minimum=0,
    maximum=14500,
    default=4200,
    **_RW_E,
    doc="Phase current in mA; maximum per version (CURRENT_MAX_MA, 14500 for a 12 A one); default 50 % of "
    "max [SIM].",
    attr="phase_current",
)
_p(
    1011,
    "Stromparameter",
    "current parameters",
    minimum=0,
    maximum=63,
    default=1,
    **_RW_E,
    doc="Bits: 1 reduction at standstill; 2 boost during acceleration above P1012; 4 boost at "
    "standstill; 8 full step above P1012; 16 SERVO fixed standstill current; 32 auto ON.",
    attr="current_parameters",
)
_p(
    1012,
    "Beschleunigung für Stromanhebung",
    "acceleration for current boost",
    kind="acceleration",
    minimum=10,
    default=10,
    **_RW_E,
    doc="Threshold for boost/full step; not below 10 rad/s².",
    attr="boost_acceleration",
)
_p(
    1034,
    "Phasenstrom Bereich",
    "phase current range",
    default=6,
    writable=False,
    write_errno=12,
    saved=True,
    doc="Factory setting: 1 1A, 2 2A, 3 3A/4A, 4 4A/SERS, 5 4A, 6 6A/8A, 7 6A/SERS, 12 12A.",
)
_p(
    1159,
    "V Stromabsenkung",
    "V current reduction",
    minimum=0,
    default=10,
    **_RW_E,
    doc="Motor speed in U/min (independent of P44) for current-regulator switching.",
)
_p(
    1033,
    "Fortsetzung nach Stop",
    "continuation after stop",
    minimum=0,
    maximum=3,
    **_RW_E,
    doc="0 restart; 1 continue; 2 jump to L65; 3 as 2, further errors ignored until P1118=0.",
    attr="continuation_after_stop",
)
_p(
    1118,
    "Flag - L65 Fehlerbehandlung",
    "flag - L65 error handling",
    minimum=0,
    maximum=1,
    doc="1 while L65 error handling runs.",
    attr="l65_flag",
)
_p(
    1031,
    "Handfahr-Kommando",
    "jog command",
    choices=frozenset({1, 2, 4, 8, 16}),
    default=None,
    readable=False,
    commands=("LS", "RS", "LF", "RF", "H"),
    doc="1 LS left slow; 2 RS right slow; 4 LF left fast; 8 RF right fast; 16 H homing.",
)
_p(
    1093,
    "Stop bei Handfahren",
    "stop on jog",
    minimum=0,
    maximum=1,
    **_RW_E,
    doc="Jog via input while a program runs: 0 interrupt and resume; 1 abort.",
    attr="stop_on_jog",
)
_p(
    1095,
    "Handfahr-Funktionen bei Power-ON",
    "jog functions at power-on",
    minimum=0,
    maximum=1,
    **_RW_E,
    doc="0 static level activates; 1 only a rising edge.",
    attr="jog_at_power_on",
)
_p(
    1035,
    "Handfahren mit Timeout",
    "jog with timeout",
    minimum=0,
    maximum=1,
    default=1,
    doc="1 = serial jog stops unless repeated within 500 ms. Not stored; 1 after power-on.",
    attr="jog_timeout",
)
_p(
    1050,
    "Eigene Antriebsadresse",
    "own drive address",
    minimum=0,
    maximum=127,
    default=1,
    writable=False,
    doc="Address from DIP switch 2 (default here 1; the device sets it).",
)
_p(
    1029,
    "Schrittüberwachung Fehler/Warnung Zuweisung",
    "step monitoring error/warning assignment",
    minimum=0,
    maximum=3,
    **_RW_E,
    doc="0 none; 1 drive error P11; 2 warning P12; 3 drive error, motor stays energized.",
    attr="step_monitoring",
)
_P1053_NAME = (
    "Option Takteingang / elektrisches Getriebe / Handrad / Encodereingang / "
    "Lastwinkelüberwachung mit Nachführung / Frequenzmessung"
)
_P1053_EN = (
    "option pulse input / electronic gear / hand wheel / encoder input / "
    "load-angle monitoring with tracking / frequency measurement"
)
_p(
    1053,
    _P1053_NAME,
    _P1053_EN,
    minimum=0,
    maximum=10,
    **_RW_E,
    doc="0 off; 1 pulses I3; 2 +direction I4; 3 quadrature I3/I4; 4 load-angle I3/I4; 5..7 as 1..3 "
    "on ENC; 8 load-angle on ENC; 9 frequency on I3 (P1124); 10 frequency on ENC.",
    attr="pulse_input",
)
_p(
    1054,
    "Wichtungsfaktor für die Eingangspulse",
    "weighting factor for input pulses",
    kind="fixed",
    decimals=5,
    minimum=-32.768,
    maximum=32.767,
    default=1,
    **_RW_E,
    doc="Unit 1/200 rev, 16 bit; outside -0.32768..0.32767 the last two decimals become 0.",
    attr="pulse_weight",
)
_p(
    1055,
    "Zeitfenster zur Messung der Frequenz",
    "time window for frequency measurement",
    minimum=1,
    default=1,
    **_RW_E,
    doc="Multiples of 2 ms.",
    attr="frequency_window",
)
_p(1057, "Max. Lastwinkel", "max. load angle", writable=False, doc="Internal (max. load angle).")
_p(
    1002,
    "Überwachungsfenster des Lastwinkels",
    "load-angle monitoring window",
    minimum=0,
    maximum=65535,
    default=255,
    **_RW_E,
    doc="Increments (1/12800 rev, unweighted); 255 = 7.2°.",
    attr="load_angle_window",
)
_p(1124, "Frequenz bei P1053=9", "frequency at P1053=9", writable=False, doc="Pulses per P1055 window.")
_p(
    1143,
    _P1053_NAME,
    _P1053_EN + " (I3/I4)",
    minimum=0,
    maximum=5,
    **_RW_E,
    doc="0 off; 1 pulses I3; 2 +direction I4; 3 quadrature; 4 load-angle I3/I4; 5 frequency (P1146).",
    attr="pulse_input2",
)
_p(
    1144,
    "Wichtungsfaktor für die Eingangspulse",
    "weighting factor for input pulses",
    kind="fixed",
    decimals=5,
    minimum=-32.768,
    maximum=32.767,
    default=1,
    **_RW_E,
    doc="As P1054 for P1143.",
    attr="pulse_weight2",
)
_p(
    1145,
    "Zeitfenster zur Messung der Frequenz",
    "time window for frequency measurement",
    minimum=1,
    default=1,
    **_RW_E,
    doc="As P1055 for P1143.",
    attr="frequency_window2",
)
_p(1146, "Frequenz bei P1143=5", "frequency at P1143=5", writable=False, doc="Pulses per P1145 window.")
_p(1147, "Takteingang Zähler 3", "pulse input counter 3", doc="Internal; do not write.")
_p(
    1094,
    "Absolutwert beibehalten bei Endschalterfehler und elektrischer Welle",
    "keep absolute value on limit error and electronic shaft",
    minimum=0,
    maximum=1,
    **_RW_E,
    doc="P1053=3/7 after a limit stop: 0 ignore blocked pulses; 1 count them.",
)
_p(1119, "Takteingang Zähler 1", "pulse input counter 1", doc="Pulse counter for P1053 modes.", attr="pulse_counter1")
_p(1120, "Takteingang Zähler 2", "pulse input counter 2", doc="As P1119.", attr="pulse_counter2")
_p(
    1149,
    "Softwareendschalter und Vergleichsposition bei P1053=7",
    "software limits and compare positions at P1053=7",
    minimum=0,
    maximum=1,
    **_RW_E,
    doc="0 ignored; 1 respected.",
)
_p(1152, "SERVO Modus", "SERVO mode", minimum=0, maximum=1, **_RW_E, doc="1 = SERVO mode (option E50/C).", attr="servo_mode")
_p(
    1153,
    "V Lastwinkel Korrektur für SERVO-Modus",
    "V load-angle correction for SERVO mode",
    minimum=0,
    default=1000,
    **_RW_E,
    doc="U/min.",
)
_p(1154, "(undokumentiert)", "(undocumented)", writable=False, doc="Listed in §4.7 without description.")
_p(1155, "(undokumentiert)", "(undocumented)", writable=False, doc="Listed in §4.7 without description.")
_p(
    1156,
    "Ist-Beschleunigung",
    "actual acceleration",
    kind="acceleration",
    writable=False,
    doc="SERVO: measured average acceleration over the ramp.",
)
_p(1157, "(undokumentiert)", "(undocumented)", writable=False, doc="Listed in §4.7 without description.")
_p(
    1158,
    "Aktuelle Abweichung vom Sollprofil",
    "current deviation from set profile",
    kind="position",
    writable=False,
    doc="SERVO: current distance deviation from the set profile.",
)
_p(
    1161,
    "In Position Fenster",
    "in-position window",
    minimum=0,
    default=128,
    **_RW_E,
    doc="SERVO in-position window in micro-steps (12800 = 360°).",
)
_p(
    1162,
    "Aufholgeschwindigkeit verwenden im SERVO-Modus",
    "use catch-up speed in SERVO mode",
    minimum=0,
    maximum=1,
    **_RW_E,
    doc="1 = catch up lost distance with P1163.",
    attr="use_catch_up_velocity",
)
_p(
    1163,
    "Aufholgeschwindigkeit im SERVO-Modus",
    "catch-up speed in SERVO mode",
    kind="velocity",
    default=3500,
    **_RW_E,
    doc="Catch-up speed (default 3500 U/min).",
    attr="catch_up_velocity",
)
_p(
    1044,
    "Stillstandsüberwachung",
    "standstill monitoring",
    kind="position",
    minimum=0,
    maximum=_POS_MAX,
    **_RW_E,
    doc="Distance within which an edge on input P1045 must occur while moving; 0 = off.",
    attr="standstill_distance",
)
_p(
    1045,
    "Stillstandsüberwachung - Zuweisung Überwachungseingang",
    "standstill monitoring input",
    minimum=1,
    maximum=8,
    default=1,
    **_RW_E,
    doc="1..8 = input I1..I8.",
    attr="standstill_input",
)
_p(
    1017,
    "Handshake Modus",
    "handshake mode",
    minimum=0,
    maximum=2,
    default=1,
    **_RW_E,
    doc="0 hardware handshake + echo; 1 no handshake + echo; 2 RS485: no echo, errors after line end.",
    attr="handshake_mode",
)
_p(
    1004,
    "E²PROM Parameter",
    "EEPROM parameters",
    choices=frozenset({2, 3, 4, 5}),
    invalid_errno=82,
    default=None,
    readable=False,
    commands=("PSAVE", "POSSAVE"),
    doc="2 PSAVE; 3 factory defaults; 4 POSSAVE (P51); 5 save R0..R5 and W.",
)
_p(
    1117,
    "Abspeichern R0 bis R5 und W",
    "save R0 to R5 and W",
    minimum=0,
    maximum=1,
    **_RW_E,
    doc="1 = PSAVE also stores R0..R5 and W.",
    attr="save_registers_too",
)
_p(
    1122,
    "Freier E²PROM Speicher",
    "free EEPROM memory",
    default=1024,
    writable=False,
    doc="Free program memory in words (x2 bytes); 1024 = empty 2 KB.",
)
_p(
    1127,
    "500µs Programm Modus",
    "500 µs program mode",
    minimum=0,
    maximum=1,
    **_RW_E,
    doc="1 = 2 ms per instruction/command (V01..V03 compatible); 0 = 500 µs.",
    attr="slow_program_cycle",
)
_p(265, "Sprachauswahl", "language selection", minimum=0, maximum=1, **_RW_E, doc="0 German; 1 English.", attr="language")
_p(
    1040,
    "Grenzposition negativ",
    "limit position negative",
    kind="position",
    minimum=_POS_MIN,
    maximum=_POS_MAX,
    **_RW_E,
    doc="Software limit negative; P1040 > P1041 -> errno 95.",
    attr="limit_negative",
)
_p(
    1041,
    "Grenzposition positiv",
    "limit position positive",
    kind="position",
    minimum=_POS_MIN,
    maximum=_POS_MAX,
    **_RW_E,
    doc="Software limit positive.",
    attr="limit_positive",
)
_p(
    1047,
    "Akkumulator",
    "accumulator",
    aliases=("X",),
    kind="fixed",
    decimals=3,
    minimum=-2147483.648,
    maximum=2147483.647,
    doc="32-bit accumulator; fixed point with 3 decimals [SIM G-ARITH].",
    attr="accumulator",
)
for _i in range(6):
    _p(
        1080 + _i,
        f"Register {_i + 1}",
        f"register {_i + 1}",
        aliases=(f"R{_i}",),
        kind="fixed",
        decimals=3,
        minimum=-2147483.648,
        maximum=2147483.647,
        saved_with_p1117=True,
        doc="Free 32-bit signed variable (3 decimals like X [SIM]); stored by PSAVE only with P1117=1.",
    )
_p(
    1092,
    "Serviceschalter extern",
    "external service switch",
    minimum=0,
    maximum=1,
    **_RW_E,
    doc="1 = the opto input 'service switch external' enables the jog inputs.",
    attr="external_service_switch",
)
_p(
    1059,
    "Paßwort Definition",
    "password definition",
    minimum=0,
    maximum=9999,
    **_RW_E,
    doc="4-digit SERS-Programmer password; 0 = none.",
)
for _i in range(9):
    _p(
        1060 + _i,
        f"Parameter Maske [{_i}]",
        f"parameter mask [{_i}]",
        minimum=0,
        maximum=65535,
        **_RW_E,
        doc="Parameters released without password (PARAMETER_MASKS).",
    )
for _i in range(4):
    _p(
        1070 + _i,
        f"Programm Maske [{_i + 1}]",
        f"program mask [{_i + 1}]",
        minimum=0,
        maximum=65535,
        **_RW_E,
        doc=f"Labels L{16 * _i + 1}..L{16 * _i + 16} released without password.",
    )
_p(1150, "CAN interface", "CAN interface", minimum=0, maximum=1, **_RW_E, doc="1 = on (variant CAN).")
_p(
    1097,
    "Operand",
    "operand",
    minimum=-(2**31),
    maximum=2**31 - 1,
    readable=False,
    doc="CANopen: operand for the opcode in P1099; never stored.",
)
_p(
    1099,
    "Opcode",
    "opcode",
    minimum=0,
    maximum=65535,
    readable=False,
    doc="CANopen: writing executes the opcode (RUN 5 = 62213, E = 63235).",
)
_p(1142, "Profibus-ID", "Profibus ID", minimum=0, maximum=1, **_RW_E, doc="0 = old ID 0008; 1 = new ID 07B5.")


ROWS = tuple(_p)
