"""SERS error numbers ("errno", P1137) and the message texts the device sends.

Source: manual §4.8.3.1 "Liste der Fehlernummern (errno)" (seed lines 2229–2357), transcribed in
spec §3.6.  The German text is kept exactly as the device sends it after the ``*`` of an error
message (§4.1); umlauts and ß stay in the Python ``str`` -- encoding (latin-1 by default, spec §7
G-ENC) happens at the wire.  The English gloss is used when P265=1 (§4.8.6.11).

Decisions (spec §7.3):

* errno 110–117 are printed in the manual with math rendering (``≤ 0``, ``$= 0$``, ``$>$``,
  ``$=$``); the device is taken to send plain ASCII: ``<= 0 erwartet``, ``= 0 erwartet``,
  ``> erwartet``, ``= erwartet``.
* errno 83 "label bereits definiert: L" -- the device presumably appends the label number; pass
  it as ``detail`` (``SersError(83, detail="5")`` -> ``label bereits definiert: L5``).

The named constants at the end cover every entry of the spec's "situation -> errno" table
(§3.6) plus the other errnos the device code raises.
"""

from __future__ import annotations

__all__ = [
    "ERRNO",
    "SersError",
    "message",
    # named errnos
    "TOO_LARGE",
    "TOO_SMALL",
    "INVALID",
    "INVALID_OUTPUT",
    "EEPROM_FULL",
    "RUN_CONSTANT_TOO_SMALL",
    "CONSTANT_TOO_LARGE",
    "UNKNOWN_IF_EVENT",
    "ACCESS_DENIED",
    "NO_PARAMETER",
    "END_OF_TEXT_EXPECTED",
    "TEXT_ONLY_IN_PGM",
    "TEXT_TOO_LONG",
    "STAR_ONLY_P1_Z",
    "DATUM_OR_Z_EXPECTED",
    "STATEMENT_EXPECTED",
    "PGM_NOT_ACTIVE",
    "IF_EVENT_EXPECTED",
    "JUMP_EXPECTED",
    "EQ_OR_QUERY_EXPECTED",
    "ON_OFF_EXPECTED",
    "CONSTANT_EXPECTED",
    "PROGRAM_RUNNING",
    "PGM_NOT_ACTIVE_2",
    "DATUM_EXPECTED",
    "CHANGE_ONLY_CONSTANT",
    "PROGRAM_NOT_RUNNING",
    "DATUM_OR_PARAMETER_EXPECTED",
    "COMMA_NOT_ALLOWED",
    "UNKNOWN_STATE",
    "SERVICE_SWITCH_ON",
    "DRIVE_ERROR_PRESENT",
    "STOP_SWITCH_ACTIVE",
    "STOP_SWITCH_OPEN",
    "NO_VALID_PROGRAM",
    "MUST_STAND",
    "JUMP_TARGET_UNKNOWN",
    "JUMP_TARGET_INVALID",
    "STACK_OVERFLOW",
    "LIMIT_OPEN",
    "NOT_ENABLED",
    "UNKNOWN_POSITIONING_MODE",
    "MUST_RUN_CONSTANT_OR_STAND",
    "INVALID_EEPROM_MODE",
    "LABEL_ALREADY_DEFINED",
    "PATH_DIFFERENCE_TOO_LARGE",
    "NEW_POSITION_TOO_LARGE",
    "NEW_POSITION_TOO_SMALL",
    "REMAINING_PATH_TOO_SHORT",
    "COMPARE1_TOO_LARGE",
    "COMPARE1_TOO_SMALL",
    "COMPARE2_TOO_LARGE",
    "COMPARE2_TOO_SMALL",
    "MODULO_TOO_LARGE",
    "NOT_WRITABLE_WHILE_MOVING",
    "NEG_LIMIT_ABOVE_POS_LIMIT",
    "RESULT_TOO_LARGE",
    "RESULT_TOO_SMALL",
    "RESULT_TOO_LARGE_TO_SHOW",
    "RESULT_TOO_SMALL_TO_SHOW",
    "DIVISION_BY_ZERO",
    "BUS_STOP_BIT",
    "NO_SUBINDEX",
    "READ_ONLY",
    "WRITE_ONLY",
    "POLY_WITH_BACKLASH",
    "NO_POLY_DATA",
    "WAIT_EXPECTED",
    "POLY_END_TOO_SHORT",
    "A_TOO_SMALL",
    "A_TOO_LARGE",
    "V_TOO_SMALL",
    "V_TOO_LARGE",
    "POLY_RELOAD_IMPOSSIBLE",
    "BUFFER_OVERFLOW",
    "STEP_ANGLE_ERROR",
]

#: errno -> (German text as sent by the device, English gloss).  Complete: 1..125.
ERRNO: dict[int, tuple[str, str]] = {
    1: ("zu groß", "too large"),
    2: ("zu klein", "too small"),
    3: ("ungültig", "invalid"),
    4: ("ungültiger Ausgang", "invalid output"),
    5: ("EEPROM Speicher voll", "EEPROM memory full"),
    6: ("EEPROM acknowledge timeout", "EEPROM acknowledge timeout"),
    7: ("EEPROM no acknowledge", "EEPROM no acknowledge"),
    8: ("EEPROM no page begin", "EEPROM no page begin"),
    9: ("run Dezimalkonstante zu klein", "run decimal constant too small"),
    10: ("Dezimalkonstante zu groß", "decimal constant too large"),
    11: ("unbekanntes if Ereignis", "unknown if event"),
    12: ("Zugriff verweigert", "access denied"),
    13: ("Parameter nicht vorhanden", "parameter does not exist"),
    14: ("adc erwartet", "adc expected"),
    15: ("Textende erwartet", "end of text expected"),
    16: ("Texteingabe nur im pgm Modus", "text input only in pgm mode"),
    17: ("Text zu lang", "text too long"),
    18: ("[Dezimalkonstante pgm psave] erwartet", "[decimal constant pgm psave] expected"),
    19: ("* nur bei P1 oder z erlaubt", "* only allowed with P1 or z"),
    20: ("Datum oder z erwartet", "datum or z expected"),
    21: ("Anweisung erwartet", "statement expected"),
    22: ("Programmiermodus nicht aktiv", "programming mode not active"),
    23: ("if erwartet", "if expected"),
    24: ("if Ereignis erwartet", "if event expected"),
    25: ("goto oder gosub oder GT oder GS erwartet", "goto or gosub or GT or GS expected"),
    26: ("goto oder gosub erwartet", "goto or gosub expected"),
    27: ("goto erwartet", "goto expected"),
    28: ("goto Dezimalkonstante erwartet", "goto decimal constant expected"),
    29: ("gosub erwartet", "gosub expected"),
    30: ("gosub Dezimalkonstante erwartet", "gosub decimal constant expected"),
    31: ("[return RT run rs rf] erwartet", "[return RT run rs rf] expected"),
    32: ("return erwartet", "return expected"),
    33: ("[Dezimalkonstante list ls lf] erwartet", "[decimal constant list ls lf] expected"),
    34: ("= oder ? erwartet", "= or ? expected"),
    35: ("[Dezimalkonstante on off] erwartet", "[decimal constant on off] expected"),
    36: ("Dezimalkonstante oder n erwartet", "decimal constant or n expected"),
    37: ("Dezimalkonstante erwartet", "decimal constant expected"),
    38: ("run erwartet", "run expected"),
    39: ("[new, neg, not] erwartet", "[new, neg, not] expected"),
    40: ("new oder neg erwartet", "new or neg expected"),
    41: ("list erwartet", "list expected"),
    42: ("quit erwartet", "quit expected"),
    43: ("off erwartet", "off expected"),
    44: ("Programm läuft noch", "program still running"),
    45: ("pgm erwartet", "pgm expected"),
    46: ("Programmiermodus nicht aktiv", "programming mode not active"),
    47: ("del erwartet", "del expected"),
    48: ("Datum erwartet", "datum expected"),
    49: ("Change: nur Konstante erlaubt", "change: only a constant allowed"),
    50: ("Dezimalkonstante oder pos erwartet", "decimal constant or pos expected"),
    51: ("pos erwartet", "pos expected"),
    52: ("psave erwartet", "psave expected"),
    53: ("[tr tron troff] erwartet", "[tr tron troff] expected"),
    54: ("Programm läuft nicht", "program not running"),
    55: ("troff erwartet", "troff expected"),
    56: ("ver erwartet", "ver expected"),
    57: ("1, 2, 3 oder 4 erwartet", "1, 2, 3 or 4 expected"),
    58: ("pos oder possave erwartet", "pos or possave expected"),
    59: ("lp erwartet", "lp expected"),
    60: ("possave erwartet", "possave expected"),
    61: ("Datum oder Parameter erwartet", "datum or parameter expected"),
    62: ("Komma nicht erlaubt", "comma not allowed"),
    63: ("not erwartet", "not expected"),
    64: ("unbekannter Zustand", "unknown state"),
    65: (
        "Programmstart nicht möglich wenn Serviceschalter an ist",
        "program start not possible while the service switch is on",
    ),
    66: (
        "Programmstart nicht möglich, Zustandsklasse-1 Fehler",
        "program start not possible, state class 1 error",
    ),
    67: ("Stop Schalter ist aktiv", "stop switch is active"),
    68: ("Stop Schalter ist offen", "stop switch is open"),
    69: ("kein gültiges Programm vorhanden", "no valid program present"),
    70: ("Antrieb muss stehen", "drive must be standing"),
    71: ("Sprungziel unbekannt", "jump target unknown"),
    72: ("Sprungziel ungültig", "jump target invalid"),
    73: ("Stack Überlauf", "stack overflow"),
    74: ("unbekannter Opcode, return vergessen ?", "unknown opcode, return forgotten ?"),
    75: ("unbekannter fxxx Opcode", "unknown fxxx opcode"),
    76: ("ungültiger Opcode für Zieladresse", "invalid opcode for target address"),
    77: ("unbekannter f7xx Opcode", "unknown f7xx opcode"),
    78: ("Endschalter offen", "limit switch open"),
    79: ("Antrieb ist nicht freigegeben", "drive is not enabled"),
    80: ("unbekannter Positioniermodus", "unknown positioning mode"),
    81: ("Antrieb muss konstant fahren oder stehen", "drive must run at constant speed or stand"),
    82: ("ungültiger EEPROM Modus Wert", "invalid EEPROM mode value"),
    83: ("label bereits definiert: L", "label already defined: L"),
    84: ("Die Wegdifferenz ist zu groß", "the path difference is too large"),
    85: ("Die neue Position ist zu groß", "the new position is too large"),
    86: ("Die neue Position ist zu klein", "the new position is too small"),
    87: ("neuer Restweg zu kurz", "new remaining path too short"),
    88: ("Vergleich Position 1 ist zu groß", "compare position 1 is too large"),
    89: ("Vergleich Position 1 ist zu klein", "compare position 1 is too small"),
    90: ("Vergleich Position 2 ist zu groß", "compare position 2 is too large"),
    91: ("Vergleich Position 2 ist zu klein", "compare position 2 is too small"),
    92: ("Der neue Modulowert ist zu groß", "the new modulo value is too large"),
    93: ("nicht schreibbar, während der Antrieb positioniert", "not writable while the drive is positioning"),
    94: (
        "Die Lötbrücke ist fuer diesen Bereich falsch eingestellt.",
        "the solder bridge is set wrongly for this range.",
    ),
    95: (
        "Die negative Grenzposition ist größer als die positive",
        "the negative limit position is greater than the positive one",
    ),
    96: ("Exponent zu groß", "exponent too large"),
    97: ("Exponent zu klein", "exponent too small"),
    98: ("Das Rechenergebnis ist zu groß", "the arithmetic result is too large"),
    99: ("Das Rechenergebnis ist zu klein", "the arithmetic result is too small"),
    100: ("Das Rechenergebnis ist zu groß zum anzeigen", "the arithmetic result is too large to display"),
    101: ("Das Rechenergebnis ist zu klein zum anzeigen", "the arithmetic result is too small to display"),
    102: ("Division durch 0", "division by 0"),
    103: ("Bus Stopbit ist aktiv", "bus stop bit is active"),
    104: ("Subindex nicht vorhanden", "subindex does not exist"),
    105: ("Wert kann nicht geschrieben werden", "value cannot be written"),
    106: ("Wert kann nicht gelesen werden", "value cannot be read"),
    107: ("Polynom mit Getriebespiel nicht erlaubt", "polynomial move with backlash not allowed"),
    108: ("Keine neuen Polynomdaten verfügbar", "no new polynomial data available"),
    109: ("Wait erwartet", "wait expected"),
    110: ("<= 0 erwartet", "<= 0 expected"),
    111: ("= 0 erwartet", "= 0 expected"),
    112: ("0 erwartet", "0 expected"),
    113: ("0 oder 1 erwartet", "0 or 1 expected"),
    114: ("> erwartet", "> expected"),
    115: ("1 erwartet", "1 expected"),
    116: ("= erwartet", "= expected"),
    117: ("3 erwartet", "3 expected"),
    118: (
        "Polynom Ende zu kurz zum Anhalten (fehlerhafte Definition Polynom Abschnitt)",
        "polynomial end too short to stop (faulty definition of polynomial segment)",
    ),
    119: ("A zu klein", "A too small"),
    120: ("A zu groß", "A too large"),
    121: ("V zu klein", "V too small"),
    122: ("V zu groß", "V too large"),
    123: ("Polynomdaten Nachladen nicht möglich", "reloading polynomial data not possible"),
    124: ("RS232 Pufferüberlauf", "RS232 buffer overflow"),
    125: ("Schrittwinkelfehler", "step angle error"),
}


def message(errno: int, english: bool = False, detail: str = "") -> str:
    """Message text for *errno* (German unless *english*, i.e. P265=1); *detail* is appended.

    Raises ``KeyError`` for an errno outside 1..125.
    """
    german, gloss = ERRNO[errno]
    return (gloss if english else german) + detail


class SersError(Exception):
    """A SERS error message: ``raise SersError(122)`` -> device sends ``*V zu groß``.

    ``detail`` is appended to the text (used by errno 83, whose text ends in ``L``).
    """

    def __init__(self, errno: int, detail: str = "") -> None:
        if errno not in ERRNO:
            raise ValueError(f"unknown SERS errno {errno}")
        self.errno = errno
        self.detail = detail
        super().__init__(errno, message(errno, detail=detail))

    def text(self, english: bool = False) -> str:
        """The message text as the device sends it (without the leading ``*``)."""
        return message(self.errno, english, self.detail)

    def __str__(self) -> str:
        return f"errno {self.errno}: {self.text()}"


# --- named errnos (spec §3.6 "situation -> errno" table and other uses) -------------------------
TOO_LARGE = 1  # value above range
TOO_SMALL = 2  # value below range
INVALID = 3  # value not in enumerated set
INVALID_OUTPUT = 4  # O5..O16 without option IO
EEPROM_FULL = 5  # program memory full
RUN_CONSTANT_TOO_SMALL = 9
CONSTANT_TOO_LARGE = 10
UNKNOWN_IF_EVENT = 11
ACCESS_DENIED = 12
NO_PARAMETER = 13  # P<n> with unknown n
END_OF_TEXT_EXPECTED = 15
TEXT_ONLY_IN_PGM = 16  # text "..." outside programming mode
TEXT_TOO_LONG = 17
STAR_ONLY_P1_Z = 19  # '*' only with P1 / Z
DATUM_OR_Z_EXPECTED = 20
STATEMENT_EXPECTED = 21  # unknown keyword / garbage
PGM_NOT_ACTIVE = 22  # DEL/C/QUIT outside programming mode
IF_EVENT_EXPECTED = 24
JUMP_EXPECTED = 25  # goto/gosub/GT/GS expected
EQ_OR_QUERY_EXPECTED = 34  # missing '=' or '?' after an address
ON_OFF_EXPECTED = 35
CONSTANT_EXPECTED = 37
PROGRAM_RUNNING = 44  # NEW/PGM/RUN while a program runs
PGM_NOT_ACTIVE_2 = 46  # second "Programmiermodus nicht aktiv"
DATUM_EXPECTED = 48
CHANGE_ONLY_CONSTANT = 49
PROGRAM_NOT_RUNNING = 54
DATUM_OR_PARAMETER_EXPECTED = 61
COMMA_NOT_ALLOWED = 62
UNKNOWN_STATE = 64
SERVICE_SWITCH_ON = 65  # program start with service switch ON
DRIVE_ERROR_PRESENT = 66  # program start with P11 != 0 ("Zustandsklasse-1 Fehler")
STOP_SWITCH_ACTIVE = 67  # input I7 "Stop" active
STOP_SWITCH_OPEN = 68  # opto STOP input open
NO_VALID_PROGRAM = 69
MUST_STAND = 70
JUMP_TARGET_UNKNOWN = 71  # GOTO/GOSUB/RUN to an undefined label
JUMP_TARGET_INVALID = 72  # label number outside 1..128
STACK_OVERFLOW = 73  # GOSUB nesting > 4
LIMIT_OPEN = 78  # move toward an open limit switch
NOT_ENABLED = 79  # move/ON while P11 != 0 or motor off
UNKNOWN_POSITIONING_MODE = 80  # P1014 not 0..3
MUST_RUN_CONSTANT_OR_STAND = 81  # W written during acceleration/deceleration
INVALID_EEPROM_MODE = 82  # P0 / P1004 value invalid
LABEL_ALREADY_DEFINED = 83  # duplicate label while storing
PATH_DIFFERENCE_TOO_LARGE = 84
NEW_POSITION_TOO_LARGE = 85
NEW_POSITION_TOO_SMALL = 86
REMAINING_PATH_TOO_SHORT = 87
COMPARE1_TOO_LARGE = 88  # P1024
COMPARE1_TOO_SMALL = 89
COMPARE2_TOO_LARGE = 90  # P1026
COMPARE2_TOO_SMALL = 91
MODULO_TOO_LARGE = 92  # P103
NOT_WRITABLE_WHILE_MOVING = 93
NEG_LIMIT_ABOVE_POS_LIMIT = 95  # P1040 > P1041
RESULT_TOO_LARGE = 98  # arithmetic overflow
RESULT_TOO_SMALL = 99  # arithmetic underflow
RESULT_TOO_LARGE_TO_SHOW = 100
RESULT_TOO_SMALL_TO_SHOW = 101
DIVISION_BY_ZERO = 102
BUS_STOP_BIT = 103
NO_SUBINDEX = 104
READ_ONLY = 105  # write to a read-only parameter
WRITE_ONLY = 106  # read of a write-only parameter
POLY_WITH_BACKLASH = 107
NO_POLY_DATA = 108  # polynomial segment not received in time
WAIT_EXPECTED = 109
POLY_END_TOO_SHORT = 118
A_TOO_SMALL = 119
A_TOO_LARGE = 120
V_TOO_SMALL = 121
V_TOO_LARGE = 122
POLY_RELOAD_IMPOSSIBLE = 123
BUFFER_OVERFLOW = 124  # > 60 characters in a line / input flood
STEP_ANGLE_ERROR = 125
