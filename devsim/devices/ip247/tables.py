"""The IP247's tables: module error numbers, machine-data and syntax error texts, the operating
modes with their pages, and the machine-data items as parameter rows (manual §4.1.1, §5.8.2, §6.2.4, §6.3.4, §7.2, §7.2.1; spec
ip247.md §3.2, §4.3–§4.5).  Texts are the manual's, verbatim; English in the second column."""

from __future__ import annotations

import msgspec

from devsim.core.kit import ErrorCode
from devsim.core.parameters import Access, Param, ParameterTable

__all__ = [
    "DATA_CHANNEL", "MACHINE_DATA", "MD_ERRORS", "MODES", "MODULE_ERRORS", "NONEXISTENT", "OBSERVE_MODES", "SYNTAX_ERRORS", "Mode", "error_codes", "mode_token",
    "page_error", "pg_code",
]

DATA_CHANNEL = 4  # page 4; pages 1 … 3 are the axes

#: Module (axis) errors (manual §7.2, spec §4.3): AG number → (German, English).  Unused
#: numbers ("frei") are not listed.
MODULE_ERRORS: dict[int, tuple[str, str]] = {
    0: ("fehlerfrei", "no error"),
    1: ("Auftragsliste PG ist VOLL", "PG job list full"),
    2: ("Nicht erlaubter Auftrag", "job not allowed"),
    3: ("Satz abgespeichert", "block stored"),
    4: ("Achse in Betrieb ==> Eingabe nicht möglich", "axis in operation, input not possible"),
    5: ("Auftragsliste AG ist voll", "AG job list full"),
    6: ("Motor wartet auf externen Start", "motor waits for external start"),
    7: ("Geschwindigkeit ausserhalb des zulässigen Bereichs", "velocity outside the permitted range"),
    8: ("Zustand nach Spannungsausfall auf der Baugruppe", "state after power failure on the module"),
    10: ("Referenzpunkt fehlt", "reference point missing"),
    12: ("Baugruppennummer mit korrekten MD nicht änderbar", "module number cannot be changed with correct MD"),
    13: ("Datenbaustein nicht vorhanden", "data block does not exist (machine data)"),
    14: ("Keine oder falsche Maschinendaten", "no or wrong machine data"),
    15: ("Fehlerhafte Maschinendaten", "faulty machine data"),
    17: ("Maschinendaten überschreiben ?", "overwrite machine data?"),
    18: ("Max. Programmzahl erreicht", "maximum number of programs reached"),
    19: ("Datenbaustein nicht vorhanden", "data block does not exist (program)"),
    20: ("Verfahrprogramm überschreiben ?", "overwrite traverse program?"),
    22: ("Multi Verfahrprog. Verarb. verboten", "multiple program processing forbidden"),
    23: ("Verfahrbereichsüberschreitung", "traverse range exceeded"),
    24: ("Zu wenig Platz für Verfahrprogramm", "too little space for the traverse program"),
    25: ("Endschalter Anfang überfahren", "limit switch 'start' overrun"),
    26: ("Endschalter Ende überfahren", "limit switch 'end' overrun"),
    27: ("externer STOP aufgetreten", "external stop occurred"),
    28: ("Software-Endschalter Anfang überfahren", "software limit 'start' overrun"),
    29: ("Software-Endschalter Ende überfahren", "software limit 'end' overrun"),
    30: ("Unzulässige Betriebsart im Teach-In", "mode not permitted in teach-in"),
    33: ("Zykluszeit überschritten", "cycle time exceeded"),
    34: ("Impulsgenerator defekt", "pulse generator defective"),
    35: ("Fehler am Satzanfang", "error at the start of a block"),
    36: ("Unterprogramm DBNr zu gross", "subprogram DB number too large"),
    37: ("G-Funktion nicht erlaubt", "G function not allowed"),
    38: ("Endlosschleife nur als äussere Schleife", "endless loop only as the outermost loop"),
    39: ("Schachtelungstiefe überschritten", "nesting depth exceeded"),
    40: ("X-Funktion falsch", "X function wrong"),
    41: ("F-Funktion falsch", "F function wrong"),
    42: ("Verfahrweg zu lang", "traverse path too long"),
    43: ("Verfahrgeschwindigkeit zu gross", "traverse velocity too large"),
    44: ("Fehler am Satzende", "error at the end of a block"),
    45: ("Programmende vor Schleifenende", "program end before loop end"),
    46: ("Unzulässige Betriebsart auf dieser Achse", "mode not permitted on this axis"),
    47: ("Keine Richtungsänderung bei fliegendem Wechsel", "no direction change in a flying change"),
    48: ("Verfahrprogramm fehlerhaft", "traverse program faulty"),
    49: ("Verfahrprogramm bereits vorhanden ! Prog-Nr. ändern", "program already exists, change its number"),
    51: ("Verfahrprogramm ist aktiv", "traverse program is active"),
    52: ("Fliegender Wechsel konnte nicht ausgeführt werden", "flying change could not be executed"),
    53: ("Leistungsteil einschalten", "switch on the power unit"),
    54: ("Fehlerhafte Generierung der Rampentabelle", "faulty generation of the ramp table"),
    55: ("AG ist ausgefallen", "PLC has failed"),
    56: ("Fehlerhafter Zugriff auf Rampentabelle", "faulty access to the ramp table"),
    57: ("Satz ist noch nicht fertig interpretiert", "block not yet completely interpreted"),
    58: ("Verfahrgeschwindigkeit zu klein", "traverse velocity too small"),
    59: ("Der Referenznocken ist defekt", "the reference cam is defective"),
    61: ("Verfahrprogramm ist nur aus dem Directory gelöscht", "program deleted from the directory only"),
    62: ("Unzulässige Wegangabe", "invalid path value"),
    63: ("Unzulässige Werkzeugkorrektur", "invalid tool offset"),
    65: ("Verfahrprogramm wartet auf Fortsetzung", "traverse program waits for continuation"),
    66: ("Wegangabe nicht BCD-codiert", "path value not BCD-coded"),
    67: ("Geschwindigkeit(sangabe) nicht BCD-codiert", "velocity not BCD-coded"),
}

#: Machine-data errors in DR n+4 (manual §7.2.1, spec §4.4).
MD_ERRORS: dict[int, str] = {
    0: "Maschinendaten sind fehlerfrei", 1: "Maschinendaten sind noch ungeprüft", 2: "Falsche Impulsdauer",
    3: "Falsche Maximalfrequenz", 4: "Falsche Tipp-/Schrittmass-Geschwindigkeit", 5: "Falsche Impulszahl/Umdrehung",
    6: "Falsche Frequenzzunahme", 7: "Falscher Software-Endschalter", 8: "Falscher Referenzpunkt",
    9: "Falsche Übersetzung", 10: "Falsche Anzahl Bestromungsmuster", 11: "Falsche Masseinheit",
    12: "Falsche Baugruppennummer", 13: "Nullpunktverschiebung zu gross", 14: "Falsche Werkzeuglängenkorrektur",
    15: "Falscher Wert für Referenzrichtung (und Synchronisation)", 16: "Rampentabelle falsch generiert",
    17: "Falsche Referenzgeschwindigkeit", 18: "Falsche Flankenbewertung", 19: "Falsche Polarität der Endschalter",
    20: "Falscher Losekompensationswert", 21: "Falsches Bereichsende", 22: "Falsche Start-Stoppfrequenz",
}

#: Traverse-program syntax errors in DW n+3 (manual §7.2, spec §4.5).
SYNTAX_ERRORS: dict[int, str] = {
    0: "kein Fehler", 1: "Text zu lang oder <LF> fehlt", 2: "Satzart falsch oder N-Funktion fehlt",
    3: "Satznummer ist zu gross", 4: "Unterprogramm-Nummer zu gross", 5: "Funktion nach G-Funktion nicht erlaubt",
    6: "Funktion nach X-Funktion nicht erlaubt", 8: "<LF> nach Schlusssatz fehlt",
    9: "Satzende: <LF> fehlt oder falsche Funktion vorhanden", 10: "Fahrweg zu gross",
    11: "Wert der F-Funktion zu gross", 12: "Zu viele Nachkommastellen", 13: "Schleifenende fehlt",
    14: "Schleifenanfang fehlt", 15: "Programmende fehlt", 16: "Funktion nicht bekannt",
    17: "Wert der M-Funktion zu gross", 18: "Neuer Satz nach Schlusssatz", 19: "Der Satz ist zu lang",
    37: "G-Funktion nicht realisiert",
}


def pg_code(error: int) -> str:
    """How COM247 shows a module error: "F" + hex of number + 80H (F8A for 10, spec §4.3)."""
    return f"F{error + 0x80:02X}"


def error_codes() -> list[ErrorCode]:
    """The module errors as reference rows (``devsim doc``)."""
    return [ErrorCode(str(n), f"{de} ({en}); PG {pg_code(n)}", "§7.2") for n, (de, en) in MODULE_ERRORS.items()]


class Mode(msgspec.Struct, frozen=True):
    """One operating mode (Betriebsart) of the table in spec §3.2."""

    number: int
    name: str
    english: str
    pages: str  # "A" axis pages, "D" data channel, "AD" both
    parameters: str = ""

    def describe(self) -> str:
        """The mode as the reference lists it: names, pages, parameters."""
        return f"{self.name} ({self.english}); pages {self.pages}" + (f"; {self.parameters}" if self.parameters else "")


def mode_token(number: int) -> str:
    """A mode's token in the tables and the reference: ``BA6``."""
    return f"BA{number}"


MODES: dict[int, Mode] = {m.number: m for m in (
    Mode(1, "Tippen Geschwindigkeit 1", "jog speed 1", "A", "W velocity (0: MD jog 1)"),
    Mode(2, "Tippen Geschwindigkeit 2", "jog speed 2", "A", "W velocity (0: MD jog 2)"),
    Mode(4, "Achse aus", "axis off", "A"),
    Mode(5, "Referenzpunkt (fahren/setzen)", "reference point (drive/set)", "A", "B 0 drive, else set"),
    Mode(6, "Schrittmaß Fahrt absolut", "incremental move absolute", "A", "DD target; W velocity"),
    Mode(7, "Schrittmaß Fahrt relativ", "incremental move relative", "A", "DD distance; W velocity"),
    Mode(8, "Automatik", "automatic", "A", "B program 0…255"),
    Mode(9, "Automatik Einzelsatz", "automatic single block", "A", "B program 0…255"),
    Mode(10, "Teach-In ein", "teach-in on", "A", "B program (new)"),
    Mode(11, "Teach-In aus", "teach-in off", "A"),
    Mode(12, "Nullpunktverschiebung absolut (Istwert setzen)", "zero offset absolute (set actual value)", "A",
         "DD new coordinate"),
    Mode(13, "Nullpunktverschiebung relativ", "zero offset relative", "A", "DD shift"),
    Mode(14, "Nullpunktverschiebung löschen", "delete zero offsets", "A"),
    Mode(15, "Werkzeugkorrektur (ein)", "tool offset on", "A", "DD tool offset"),
    Mode(16, "Werkzeugkorrektur aus", "tool offset off", "A"),
    Mode(17, "Fehler löschen", "clear errors", "AD"),
    Mode(20, "Maschinendaten Eingabe", "machine data input", "A", "MD record, DB number"),
    Mode(21, "Maschinendaten Löschen", "machine data delete", "A", "DB number"),
    Mode(22, "Verfahrprogramm Eingabe", "traverse program input", "D", "program record, number"),
    Mode(23, "Verfahrprogramm Löschen", "traverse program delete", "D", "program number"),
    Mode(24, "SYS-ID Eingabe", "module identification input", "D", "module, slot, page"),
    Mode(64, "Maschinendatendirectory Lesen", "read machine-data directory", "AD"),
    Mode(65, "Verfahrprogrammdirectory Lesen", "read program directory", "AD"),
    Mode(66, "Istwerte Lesen", "read actual values", "A", "BCD flag"),
    Mode(67, "Maschinendaten Lesen", "read machine data", "AD", "DB number"),
    Mode(68, "Maschinendatenübersicht", "machine-data overview", "AD"),
    Mode(69, "Verfahrprogramm Lesen", "read traverse program", "AD", "program number"),
    Mode(70, "SYS-ID Lesen", "read module identification", "AD"),
    Mode(71, "Lageistwert (Beobachten)", "observe actual position", "A"),
    Mode(73, "Restweg (Beobachten)", "observe residual distance", "A"),
)}
#: The observe modes (manual §4.4: "Beobachtbetriebsarten sind: 66 Istwerte Lesen, 71 Lage-Istwert,
#: 73 Restweg, 74 Beobachtung ausschalten"): they leave the pending error as it is (§4.1).
OBSERVE_MODES = frozenset((66, 71, 73, 74))
#: Accepted by FB164 but not existing: negatively acknowledged on every page (spec §3.2).
NONEXISTENT = frozenset((3, 18, 19, 72))


def page_error(mode: int, page: int, *, md_numbers_differ: bool = False) -> int | None:
    """The module error a mode gets on a page (spec §3.2 page rules): 2 for a mode that does not
    exist, 46 for a mode not permitted on this page, None when it may run there."""
    if page == DATA_CHANNEL and 1 <= mode <= 16:
        return 46  # §6.2.4 "Auf dem Datenkanal werden zusätzlich auch die Betriebsarten 1-16 negativ quittiert"
    if mode in NONEXISTENT or mode not in MODES:
        return 2
    pages = MODES[mode].pages
    if page == DATA_CHANNEL:
        if mode == 67:
            return None if md_numbers_differ else 46
        return None if "D" in pages else 46
    return None if "A" in pages else 46


def _md(key: str, name: str, doc: str, unit: str = "", minimum: float | None = None, maximum: float | None = None,
        *, attr: str, access: Access = "rw") -> Param:
    return Param(key, name, "§4.8", doc, unit=unit, minimum=minimum, maximum=maximum, default=None, access=access,
                 attr=attr)


#: The machine data of an axis (spec §4.8; manual §5.6.1.2, §6.3.8.1), one row per item, keyed by
#: its place in the 70-word record as the host writes it (``n+5/6``: the double word 5 and 6,
#: ``n+3 DL``: the left byte of word 3).  ``attr`` names the item's value on
#: :class:`.machine_data.MachineData`, which the model reads; the record's layout and the checks
#: that give the MD errors are :mod:`.machine_data`'s.
MACHINE_DATA = ParameterTable([
    _md("n+3 DR", "Achse", "axis number", "", 1, 3, attr="axis"),
    _md("n+3 DL", "Baugruppe", "module number (= SYS-ID module)", "", 0, 99, attr="module"),
    _md("n+4 DL", "Masseinheit", "unit: 1 mm, 2 0.1 inch, 3 degree", "", 1, 3, attr="unit"),
    _md("n+46", "Achstyp", "axis type: 00H linear, 80H rotary", "", attr="rotary"),
    _md("n+5/6", "Maximale Frequenz", "maximum frequency f_max", "Hz", 40, 100_000, attr="f_max"),
    _md("n+7/8", "Start/Stop Frequenz", "start/stop frequency f_ss", "Hz", 1, 10_000, attr="f_ss"),
    _md("n+9/10", "Frequenz-Zunahme", "frequency increase a", "mHz/ms", 20, 2_599_999, attr="a"),
    _md("n+11", "Impulsdauer", "pulse duration", "µs", 1, 31, attr="pulse_us"),
    _md("n+12", "Polarität", "pulse polarity: 40H positive edge, 00H negative edge", "", attr="pulse_polarity"),
    _md("n+13", "Bestromungsmusteranzahl", "number of current patterns", "", 4, 40, attr="patterns"),
    _md("n+14", "Imp/Umdrehung", "pulses per motor revolution", "1/rev", 12, 1000, attr="pulses_per_rev"),
    _md("n+15/16", "Übersetzung", "travel per motor revolution (gear)", "base/rev", 12, 400_000, attr="gear"),
    _md("n+17/18", "Tippgeschwindigkeit 1", "jog velocity 1", "unit/min", 1, 65000, attr="jog1"),
    _md("n+19/20", "Tippgeschwindigkeit 2", "jog velocity 2", "unit/min", 1, 65000, attr="jog2"),
    _md("n+21/22", "Schrittgeschwindigkeit", "incremental (step) velocity", "unit/min", 1, 65000,
        attr="step_velocity"),
    _md("n+23/24", "Referenzgeschwindigkeit", "reference velocity", "unit/min", 1, 65000, attr="reference_velocity"),
    _md("n+25", "Referenzpunkt synchron", "reference synchronous: 0 yes, 1 no", "", 0, 1, attr="reference_sync"),
    _md("n+26", "Referenzrichtung", "reference direction: 00H forward, 20H backward", "",
        attr="reference_direction"),
    _md("n+27/28", "Referenzpunkt Koordinate", "reference coordinate x_ref", "base", -99_999_999, 99_999_999,
        attr="reference"),
    _md("n+29/30", "Software Endschalter Anfang", "SW limit start (rotary: range start)", "base",
        -99_999_999, 99_999_999, attr="limit_begin"),
    _md("n+31/32", "Software Endschalter Ende", "SW limit end (rotary: range end)", "base",
        -99_999_999, 99_999_999, attr="limit_end"),
    _md("n+33", "Polarität Endschalter", "limit-switch polarity: 0 NO contact, 1 NC contact", "", 0, 1,
        attr="limit_polarity"),
    _md("n+34/35", "Werkzeuglängen Korrektur", "tool length correction (G43/G44)", "base",
        -99_999_999, 99_999_999, attr="tool_length"),
    _md("n+36/37", "Losekompensation", "backlash", "base", 0, 64_999, attr="backlash"),
    *(_md(f"n+{38 + 2 * i}/{39 + 2 * i}", f"Nullpunkt Verschiebung {i + 1}", f"zero offset {i + 1} (G{54 + i})",
          "base", -99_999_999, 99_999_999, attr=f"zero_offset_{i + 1}") for i in range(4)),
    _md("n+47", "AG BCD codiert", "PLC values BCD-coded: 01H yes, 00H no", "", attr="bcd"),
    _md("n+4 DR", "MD-Fehler", "machine-data error (written by the module)", "", 0, 22, attr="error", access="r"),
], name="machine-data item")
