"""SERS non-volatile memory through a real pty: PSAVE/POSSAVE/P1004, power-on values,
program storage (T-20), simulator restarts and `kill -9` during EEPROM writes
(sers.md §3.5.9, §3.5.12, §4.1, §4.9, T-20, T-21)."""

from __future__ import annotations

import copy
import json
import os
import queue
import random
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
import serial

from devsim.devices.sers.statements import ALIAS_WORDS, KEYWORDS
from tests.sers.conftest import Host, Plant, start_plant
from tests.support.memory import killed_at_write

ROOT = Path(__file__).resolve().parents[2]
DEG = 12800 / 360
LIST_ROW = re.compile(r"(\d+): (.*)")


def power_cycle(plant: Plant, wipe: bool = False) -> None:
    plant.runtime.power_cycle(plant.name, wipe=wipe)
    plant.advance(2.0)  # display '-' for 2 s, input discarded meanwhile (§4.1)


def query(host: Host, name: str) -> str:
    """``#<name>?`` → the value text of the answer (after ``=``), checking the framing."""
    answer = host.ask(f"#{name}?\r").decode("latin-1")
    match = re.fullmatch(rf"#{re.escape(name)}\?\r{re.escape(name.upper())}=(.*)\n\r\nok\d\n\r", answer)
    assert match, f"unexpected answer to {name}?: {answer!r}"
    return match.group(1)


def normalise(statement: str) -> str:
    """``W=360.0000`` and ``W=360`` are the same stored constant (G-LIST decimals)."""
    return re.sub(r"(\d)\.0+\b", r"\1", statement.strip())


def listing(host: Host) -> list[tuple[int, str]]:
    """``#LIST`` → [(number, statement)]; checks every row is ``<n>: <statement>\\n\\r``."""
    answer = host.ask("#LIST\r").decode("latin-1")
    assert answer.startswith("#LIST\r"), answer
    body, ack = re.fullmatch(r"#LIST\r(.*?)(\n(?:ok\d|pgm)\n\r)", answer, re.S).groups()
    rows = body.split("\n\r")
    assert rows[-1] == "", f"listing does not end with LF CR: {answer!r}"
    result = []
    for row in rows[:-1]:
        match = LIST_ROW.fullmatch(row)
        assert match, f"garbage row {row!r} in listing {answer!r}"
        result.append((int(match.group(1)), normalise(match.group(2))))
    return result


def cost(statement: str) -> int:
    """Bytes of a statement in the spec's memory model (§4.9 G-MEM)."""
    return 6 if any(ch.isdigit() for ch in statement) else 2


# ======================================================================================
# parameters
# ======================================================================================
@pytest.mark.manual("§4.8.6.10", "P1004=2 / PSAVE stores the parameters from RAM in the EEPROM")
@pytest.mark.parametrize("save", ["PSAVE", "P1004=2"])
def test_psave_keeps_parameters_across_power_cycle(plant_factory, tmp_path, save: str) -> None:
    plant = plant_factory({}, state_dir=tmp_path)
    host = plant.host
    assert host.ask("#P1019=45 V=500 P1028=9\r") == b"#P1019=45 V=500 P1028=9\r\nok1\n\r"
    assert host.ask(f"#{save}\r") == f"#{save}\r\nok1\n\r".encode()
    power_cycle(plant)
    assert query(host, "P1019") == "45U/min"
    assert query(host, "V") == "500U/min"
    assert query(host, "P1028") == "9"


@pytest.mark.manual("§4.8.6.10", "changed parameters are only in RAM until PSAVE: switching off without PSAVE loses them")
def test_change_without_psave_reverts_after_power_cycle(plant_factory, tmp_path) -> None:
    plant = plant_factory({}, state_dir=tmp_path)
    host = plant.host
    host.ask("#P1019=45\r")
    host.ask("#PSAVE\r")
    assert host.ask("#P1019=60 V=700\r") == b"#P1019=60 V=700\r\nok1\n\r"
    assert query(host, "P1019") == "60U/min"  # RAM has the new value ...
    power_cycle(plant)
    assert query(host, "P1019") == "45U/min"  # ... the EEPROM the saved one
    assert query(host, "V") == "100U/min"  # never saved: factory default


@pytest.mark.manual("§4.8.6.10", "P1004=3 replaces all stored parameters by the factory defaults")
def test_p1004_3_restores_factory_defaults(plant_factory, tmp_path) -> None:
    plant = plant_factory({}, state_dir=tmp_path)
    host = plant.host
    host.ask("#P1019=45 V=500\r")
    host.ask("#PSAVE\r")
    power_cycle(plant)
    assert query(host, "P1019") == "45U/min"
    assert host.ask("#P1004=3\r") == b"#P1004=3\r\nok1\n\r"
    assert query(host, "P1019") == "30U/min"  # RAM too [SIM, §4.9]
    assert query(host, "V") == "100U/min"
    power_cycle(plant)
    assert query(host, "P1019") == "30U/min"  # EEPROM parameters were destroyed
    assert query(host, "V") == "100U/min"


@pytest.mark.manual("§4.8.6.10", "P1004=4 / POSSAVE stores the actual position P51 in the EEPROM")
def test_possave_restores_p51(plant_factory, tmp_path) -> None:
    plant = plant_factory({}, state_dir=tmp_path)
    host = plant.host
    host.ask("#ON W=720 E\r")
    plant.settle()
    assert query(host, "P51") == "720°"
    assert host.ask("#POSSAVE\r") == b"#POSSAVE\r\nok1\n\r"
    host.ask("#W=90 E\r")
    plant.settle()
    assert query(host, "P51") == "810°"
    power_cycle(plant)
    assert query(host, "P51") == "720°"  # the saved position, not the last one
    assert plant.read("energized") is False


def test_without_possave_p51_is_zero_after_power_cycle(plant_factory, tmp_path) -> None:
    plant = plant_factory({}, state_dir=tmp_path)
    host = plant.host
    host.ask("#ON W=720 E\r")
    plant.settle()
    host.ask("#PSAVE\r")  # PSAVE does not store the position
    assert query(host, "P51") == "720°"
    power_cycle(plant)
    assert query(host, "P51") == "0°"


@pytest.mark.manual("§4.8.6.4", "P1035 is not stored in the EEPROM: after every power-on P1035=1")
@pytest.mark.manual("§4.8.5.5", "P1110 is 1 after switching on and not stored")
@pytest.mark.manual("§4.8.3.2", "P403 = 3 after a power-on reset")
def test_non_stored_parameters_take_power_on_values(plant_factory, tmp_path) -> None:
    plant = plant_factory({"axis": {"reference_low": 20 * DEG}}, state_dir=tmp_path)
    host = plant.host
    host.ask("#ON H\r")
    plant.settle()
    assert query(host, "P403") == "0"  # homed
    assert host.ask("#P1035=0 P1110=0 W=500 R0=1.5\r") == b"#P1035=0 P1110=0 W=500 R0=1.5\r\nok1\n\r"
    host.ask("#P1019=45\r")
    host.ask("#PSAVE\r")
    assert (query(host, "P1035"), query(host, "P1110"), query(host, "W")) == ("0", "0", "500°")
    power_cycle(plant)
    assert query(host, "P1019") == "45U/min"  # the PSAVE did happen
    assert query(host, "P1035") == "1"
    assert query(host, "P1110") == "1"
    assert query(host, "W") == "0°"  # P1117=0: W not stored
    assert query(host, "R0") == "0"
    assert query(host, "P403") == "3"  # no valid reference after power-on


@pytest.mark.manual("§4.8.6.10", "P1117=1: PSAVE also stores R0..R5 and W")
@pytest.mark.manual("§4.6.6", "W is 0 after power-on unless P1117=1 and W was stored with PSAVE")
def test_p1117_makes_psave_keep_w_and_registers(plant_factory, tmp_path) -> None:
    plant = plant_factory({}, state_dir=tmp_path)
    host = plant.host
    line = "#P1117=1 W=500 R0=1.5 R5=-2.25\r"
    assert host.ask(line) == line.encode() + b"\nok1\n\r"
    host.ask("#PSAVE\r")
    host.ask("#W=7 R0=3 R5=4\r")  # changed after the save: not kept
    power_cycle(plant)
    assert query(host, "P1117") == "1"
    assert query(host, "W") == "500°"
    assert query(host, "R0") == "1.5"
    assert query(host, "R5") == "-2.25"


def test_restart_of_the_simulator_keeps_saved_values_and_program(plant_factory, tmp_path) -> None:
    first = plant_factory({}, state_dir=tmp_path)
    host = first.host
    host.ask("#P1019=45 V=500\r")
    host.ask("#PSAVE\r")
    host.ask("#P51=123.75\r")  # 4400 increments: representable exactly (§5.1)
    host.ask("#POSSAVE\r")
    host.ask("#NEW\r")
    host.ask("#ON V=20\r")
    host.ask("#W=360 E\r")
    host.ask("#QUIT\r")
    host.ask("#P1020=99\r")  # not saved
    first.host.close()
    first.runtime.stop()

    second = plant_factory({}, state_dir=tmp_path)
    host = second.host
    assert query(host, "P1019") == "45U/min"
    assert query(host, "V") == "500U/min"
    assert query(host, "P1020") == "300U/min"
    assert query(host, "P51") == "123.75°"
    assert listing(host) == [(1, "ON"), (2, "V=20"), (3, "W=360"), (4, "E")]
    assert query(host, "P1122") == str(1024 - (2 + 6 + 6 + 2) // 2)


def test_power_cycle_with_wipe_erases_everything(plant_factory, tmp_path) -> None:
    plant = plant_factory({}, state_dir=tmp_path)
    host = plant.host
    host.ask("#P1019=45 P1117=1 W=500\r")
    host.ask("#PSAVE\r")
    host.ask("#P51=90\r")
    host.ask("#POSSAVE\r")
    host.ask("#NEW\r")
    host.ask("#ON\r")
    host.ask("#QUIT\r")
    power_cycle(plant)
    assert query(host, "P1019") == "45U/min"  # stored before the wipe ...
    assert query(host, "P1122") == "1023"
    power_cycle(plant, wipe=True)
    assert query(host, "P1019") == "30U/min"  # ... and gone after it
    assert query(host, "P1117") == "0"
    assert query(host, "W") == "0°"
    assert query(host, "P51") == "0°"
    assert query(host, "P1122") == "1024"
    assert listing(host) == []
    image = json.loads((tmp_path / "sers.nvram.json").read_text("utf-8"))
    assert not image.get("params") and not image.get("position")
    assert not image.get("program", {}).get("lines")


# ======================================================================================
# programming mode (T-20, T-21)
# ======================================================================================
def test_t20_programming_mode(plant_factory, tmp_path) -> None:
    plant = plant_factory({}, state_dir=tmp_path)
    host = plant.host
    assert query(host, "P1122") == "1024"
    assert host.ask("#NEW\r") == b"#NEW\r\npgm\n\r"
    assert host.ask("#ON\r") == b"#ON\r\npgm\n\r"
    assert plant.read("energized") is False  # stored, not executed
    assert plant.read("display") == {"char": "4", "blinking": False}
    assert host.ask("#W=360 E\r") == b"#W=360 E\r\npgm\n\r"
    assert plant.read("motion.kind") is None
    assert plant.read("param.W") == 0  # the assignment went into the program, not into W
    answer = host.ask("#LIST\r")
    assert answer.endswith(b"\npgm\n\r")  # LIST is executed, still in programming mode
    assert listing(host) == [(1, "ON"), (2, "W=360"), (3, "E")]
    assert host.ask("#QUIT\r") == b"#QUIT\r\nok1\n\r"
    assert plant.read("energized") is False
    assert host.ask("#P0?\r") == b"#P0?\rP0=0\n\r\nok1\n\r"
    # the program survives a power cycle, and takes 2 + 6 + 2 bytes = 5 words (G-MEM)
    power_cycle(plant)
    assert listing(host) == [(1, "ON"), (2, "W=360"), (3, "E")]
    assert query(host, "P1122") == "1019"


def test_t21_listing_one_statement_per_row(sers: Plant) -> None:
    host = sers.host
    host.ask("#NEW\r")
    assert host.ask("#1 ON V=1000 W=5000 E\r") == b"#1 ON V=1000 W=5000 E\r\npgm\n\r"
    assert host.ask("#O1=1 D=10 W=2000 E\r") == b"#O1=1 D=10 W=2000 E\r\npgm\n\r"
    host.ask("#QUIT\r")
    assert listing(host) == [
        (1, "ON"), (2, "V=1000"), (3, "W=5000"), (4, "E"),
        (5, "O1=1"), (6, "D=10"), (7, "W=2000"), (8, "E"),
    ]
    assert sers.read("output.O1") is False  # stored, not executed
    host.ask("#P1028=9\r")  # bit 3: the user's lines, numbered by their first statement
    assert listing(host) == [(1, "ON V=1000 W=5000 E"), (5, "O1=1 D=10 W=2000 E")]


@pytest.mark.manual("§4.8.2.1", "P0=2 (NEW) starts programming mode and deletes the old EEPROM program")
def test_new_deletes_the_old_program(plant_factory, tmp_path) -> None:
    plant = plant_factory({}, state_dir=tmp_path)
    host = plant.host
    host.ask("#NEW\r")
    host.ask("#ON W=360 E\r")
    host.ask("#QUIT\r")
    host.ask("#NEW\r")
    host.ask("#OFF\r")
    host.ask("#QUIT\r")
    power_cycle(plant)
    assert listing(host) == [(1, "OFF")]
    assert query(host, "P1122") == "1023"


def _stored_program(state_dir: Path, options: list[str], lines: int) -> dict:
    """The state file of a drive (``options``) after ``lines`` lines of ten 6-byte statements typed
    through its port (G-MEM), the parameters with R0..R5 and W saved (PSAVE with P1117=1) and the
    position (POSSAVE)."""
    plant = start_plant([{"options": options}], state_dir=state_dir)
    host = plant.host
    host.ask("#NEW\r")
    for _ in range(lines):
        assert host.ask("#" + " ".join(["O1=1"] * 10) + "\r").endswith(b"\npgm\n\r")
    host.ask("#QUIT\r")
    for command in ("#P1019=45 P1117=1 W=500\r", "#PSAVE\r", "#P51=90\r", "#POSSAVE\r"):
        assert host.ask(command).endswith(b"\nok1\n\r")
    plant.host.close()
    plant.runtime.stop()
    return json.loads((state_dir / "sers.nvram.json").read_text("utf-8"))


#: What a drive without a valid program answers ``RUN`` (errno 69, spec §4.4 "valid program").
NO_VALID_PROGRAM = b"#RUN\r\n*kein g\xfcltiges Programm vorhanden\n\r"


def _without_a_valid_program(plant: Plant, state_file: Path, text: str, capfd: pytest.CaptureFixture[str],
                             why: str) -> None:
    """The drive started on ``state_file`` (holding ``text``) has no valid program: ``RUN`` is
    errno 69, LIST lists nothing, one stderr line names the file and ``why``, the file is as it
    was, and the parameters are the ones stored."""
    assert plant.host.ask("#RUN\r") == NO_VALID_PROGRAM
    assert re.fullmatch(rb"#LIST\r\nok\d\n\r", plant.host.ask("#LIST\r"))  # (no statement listed)
    err = capfd.readouterr().err
    assert f"devsim: memory {state_file}: " in err and why in err and "the program fails its checksum" in err
    assert state_file.read_text("utf-8") == text
    assert query(plant.host, "P1019") == "45U/min"


@pytest.mark.manual("§4.4", "program memory 2 KByte standard, 8 KByte with option P8")
def test_a_program_longer_than_the_drives_memory_fails_its_checksum(plant_factory, tmp_path, capfd) -> None:
    """[SIM-CHOICE, as the kind's parameters] 35 lines of ten statements (2100 bytes) stored by a
    drive with option P8, then a drive without it on that file: it starts without a valid program
    (before: option P8 left the memory at 2 KB, so errno 5 refused the 35th line; and a program
    longer than the memory loaded); with P8 it loads, 8 KB less the program free (P1122 in words)."""
    _stored_program(tmp_path, ["P8"], 35)
    state_file = tmp_path / "sers.nvram.json"
    text = state_file.read_text("utf-8")
    capfd.readouterr()
    without_p8 = start_plant([{}], state_dir=tmp_path)
    try:
        _without_a_valid_program(without_p8, state_file, text, capfd,
                                 "the stored program of 2100 bytes is longer than the drive's 2048-byte program memory")
    finally:
        without_p8.host.close()
        without_p8.runtime.stop()  # (its memory is free for the next drive)
    plant = plant_factory({"options": ["P8"]}, state_dir=tmp_path)
    assert query(plant.host, "P1122") == str((8192 - 2100) // 2)
    assert plant.host.ask("#RUN\r") != NO_VALID_PROGRAM


@pytest.fixture(scope="module")
def typed(tmp_path_factory: pytest.TempPathFactory) -> dict:
    """The state file of a drive with one program line typed through its port."""
    return _stored_program(tmp_path_factory.mktemp("sers-typed"), [], 1)


@pytest.mark.parametrize("program", [None, {}, [], 0, "", {"lines": None}, {"lines": {}}, {"lines": [[]]},
                                     {"lines": [["O1=1"], [5]]}, {"lines": [["O1=1"]], "x": 0}])
def test_a_program_the_drive_never_stores_fails_its_checksum(plant_factory, tmp_path, capfd, typed: dict,
                                                              program: object) -> None:
    """[SIM-CHOICE, as the kind's parameters] (Before: null, ``{}``, ``[]``, 0 or ``""`` read as
    no program without a word, a number as the statement ``'5'``, an empty line listed nothing.)"""
    state_file = tmp_path / "sers.nvram.json"
    text = json.dumps({**typed, "program": program})
    state_file.write_text(text, "utf-8")
    _without_a_valid_program(plant_factory({}, state_dir=tmp_path), state_file, text, capfd,
                             "not what the device writes" if type(program) is not dict or "x" in program
                             or program == {} else "are no lines of statements the drive stores")


@pytest.mark.manual("§4.2", "Im Programmiermodus werden Anweisungen wie LIST, DEL, TR, C, nicht gespeichert")
@pytest.mark.parametrize(("lines", "why"), [
    ([["O1=1"], ["XYZ 12"]], "'XYZ 12' is one the drive refuses when it is typed (errno 34: = oder ? erwartet)"),
    ([["IF I17"]], "errno 11: unbekanntes if Ereignis"),
    ([["L200"]], "errno 72"),
    ([["+3000000"]], "errno 10"),
    ([["O1=1 O2=1"]], "it is not one statement as the drive stores it"),
    ([[" O1=1"]], "it is not one statement as the drive stores it"),
    ([["O1=1", "LIST"]], "'LIST' is one the drive refuses when it is typed (programming mode does not store it)"),
    ([["QUIT"]], "programming mode does not store it"),
    ([["P0=0"]], "programming mode does not store it"),
    ([["C 5"]], "programming mode does not store it"),
    ([["// a note"]], "programming mode does not store it"),
    ([['"a#b"']], "no line of 60 latin-1 characters carries it"),
    ([['"' + "x" * 60 + '"']], "no line of 60 latin-1 characters carries it"),
    ([["L5", "O1=1"], ["L5"]], "the stored program defines a label twice (errno 83: label bereits definiert: L5)"),
])
def test_a_program_with_a_statement_the_drive_refuses_when_typed_fails_its_checksum(
        plant_factory, tmp_path, capfd, typed: dict, lines: list, why: str) -> None:
    """[SIM-CHOICE, as the kind's parameters] A state file whose program holds a statement the
    drive's programming mode refuses or does not store (read by the same statement reader and
    the same table of what programming mode runs instead, §4.2; a label defined twice, errno 83
    §4.6.2; a text no line carries): no valid program.  (Before: such a program loaded; ``XYZ 12``
    and ``LIST`` were passed over when it ran, the second ``L5`` was never jumped to.)"""
    state_file = tmp_path / "sers.nvram.json"
    text = json.dumps({**typed, "program": {"lines": lines}})
    state_file.write_text(text, "utf-8")
    _without_a_valid_program(plant_factory({}, state_dir=tmp_path), state_file, text, capfd, why)


#: One stored statement of every form the language has (§4.2 "Anweisung"), by its row of
#: ``statements.KEYWORDS`` (an alias: an assignment and a query), or its form without a keyword.
_EVERY_STATEMENT = {
    **{word: f"{word}=1" for word in ALIAS_WORDS},
    "NOT": "NOT", "NEG": "NEG", "E": "E", "H": "H", "S": "S", "ON": "ON", "OFF": "OFF", "PSAVE": "PSAVE",
    "POSSAVE": "POSSAVE", "POS0": "POS0", "POSR": "POSR", "NEW": "NEW", "PGM": "PGM", "PE": "PE", "VER": "VER",
    "TRON": "TRON", "TROFF": "TROFF", "RETURN": "RETURN", "RT": "RT", "IF": "IF P12<>0 THEN", "ELSE": "ELSE",
    "END": "END", "WAIT": "WAIT !I1", "GOTO": "GOTO 1", "GT": "GT1", "GOSUB": "GOSUB 2", "GS": "GS2",
    "RUN": "RUN 2", "RS": "RS:I3", "RF": "RF", "LS": "LS:I4=0", "LF": "LF",
    "label": "L 2", "text": '"Durchmesser"', "arithmetic": "+P1019", "parameter": "P1019=45", "output": "O2=1",
    "query": "V?", "name query": "P12??", "legacy IF": "IF IN5", "star": "Z=*", "arithmetic constant": "-2147483.639",
}
#: The rows programming mode runs instead of storing (§4.2), and THEN (errno 23 without IF).
_NEVER_STORED = {"TR", "QUIT", "DEL", "LIST", "LISTP", "THEN"}


def test_every_statement_the_drive_stores_when_typed_loads_again(plant_factory, tmp_path, capfd) -> None:
    """Every form of statement typed in programming mode (one per line, a line joined to the
    next with ';', a line of several), saved in the state file, loads as it was saved: a valid
    program (``RUN`` runs it: its first statement PE ends it), the same lines, nothing on stderr.
    The table covers every keyword of the statement reader."""
    assert {row.token for row in KEYWORDS} - _NEVER_STORED <= set(_EVERY_STATEMENT)
    state_file = tmp_path / "sers.nvram.json"
    typing = start_plant([{}], state_dir=tmp_path)
    try:
        assert typing.host.ask("#NEW\r") == b"#NEW\r\npgm\n\r"
        for text in ["PE", *_EVERY_STATEMENT.values(), "L1 ON;", "W=360 E // a note", "L3"]:
            assert typing.host.ask(f"#{text}\r").endswith(b"\npgm\n\r"), text
        assert typing.host.ask("#QUIT\r").endswith(b"\nok1\n\r")
        free = query(typing.host, "P1122")
    finally:
        typing.host.close()
        typing.runtime.stop()
    saved = state_file.read_text("utf-8")
    lines = json.loads(saved)["program"]["lines"]
    assert lines[0] == ["PE"] and lines[-2:] == [["L1", "ON", "W=360", "E"], ["L3"]]  # (no comment stored)
    assert len(lines) == 1 + len(_EVERY_STATEMENT) + 2
    capfd.readouterr()
    plant = plant_factory({}, state_dir=tmp_path)
    assert plant.host.ask("#RUN\r") == b"#RUN\r\nok1\n\r"
    assert plant.read("program") == lines and query(plant.host, "P1122") == free
    assert "devsim: memory" not in capfd.readouterr().err
    assert state_file.read_text("utf-8") == saved


def test_the_eeprom_a_drive_saved_loads_as_it_was_saved(plant_factory, tmp_path, typed: dict) -> None:
    (tmp_path / "sers.nvram.json").write_text(json.dumps(typed), "utf-8")
    plant = plant_factory({}, state_dir=tmp_path)
    assert plant.read("display")["char"] != "7"
    assert (query(plant.host, "P1019"), query(plant.host, "W"), query(plant.host, "P51")) == ("45U/min", "500°", "90°")


@pytest.mark.parametrize(("section", "value"), [
    ("params", None), ("params", {}), ("registers", None), ("registers", {}), ("registers", []),
    ("registers", {"47": 0}), ("registers", "without 1085"), ("registers", "with 1086"), ("position", None),
    ("position", "90"),
])
def test_an_eeprom_section_the_drive_never_writes_reads_as_a_checksum_error(
        plant_factory, tmp_path, capfd, typed: dict, section: str, value: object) -> None:
    """[SIM-CHOICE, as for a stored value PSAVE never writes] The drive's own file with a section
    PSAVE, P1004=5 or POSSAVE never writes (null, empty, R0..R5 and W not all seven, a position
    that is no number): the EEPROM fails its checksum (display 7) and stderr names the file.
    Before: params null or {} read as no PSAVE, missing registers as 0, a position "90" as none,
    not a word said."""
    image = copy.deepcopy(typed)
    if value == "without 1085":
        del image["registers"]["1085"]
    elif value == "with 1086":
        image["registers"]["1086"] = 0
    else:
        image[section] = value
    (tmp_path / "sers.nvram.json").write_text(json.dumps(image), "utf-8")
    plant = plant_factory({}, state_dir=tmp_path)
    assert plant.read("display") == {"char": "7", "blinking": False}
    assert f"devsim: memory {tmp_path / 'sers.nvram.json'}: " in capfd.readouterr().err


# ======================================================================================
# kill -9 while the EEPROM is written
# ======================================================================================
class SimProcess:
    """``devsim run sers --pty --state-dir DIR`` as a separate process (real time)."""

    def __init__(self, state_dir: Path, config: Path) -> None:
        env = dict(os.environ)
        env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH", "")) if p)
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "devsim", "run", "sers", "--pty", "--config", str(config),
             "--state-dir", str(state_dir)],
            cwd=ROOT,
            env=env,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            text=True,
        )
        self._lines: queue.Queue[str | None] = queue.Queue()
        threading.Thread(target=self._pump, daemon=True).start()
        self.path = self._pty_path()

    def _pump(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            self._lines.put(line.rstrip("\n"))
        self._lines.put(None)

    def _pty_path(self, timeout: float = 15.0) -> str:
        deadline = time.monotonic() + timeout
        while True:
            try:
                line = self._lines.get(timeout=max(0.01, deadline - time.monotonic()))
            except queue.Empty:
                self.kill()
                raise AssertionError("the simulator printed no 'sers: pty' line") from None
            assert line is not None, f"the simulator ended early (exit {self.proc.wait()})"
            if line.startswith("sers: pty "):
                return line.split(" ", 2)[2]

    def kill(self) -> None:
        if self.proc.poll() is None:
            os.kill(self.proc.pid, signal.SIGKILL)
        self.proc.wait(timeout=15)
        if self.proc.stdout is not None:
            self.proc.stdout.close()


ACKED = re.compile(rb"\nok\d\n\r|\npgm\n\r")


def stream_and_kill(
    sim: SimProcess, lines: list[str], kill_after: int, phase: float, window: int = 3
) -> tuple[int, int]:
    """Send ``lines`` back to back, keeping ``window`` of them unacknowledged so that the drive
    always has work queued, and SIGKILL the simulator once ``kill_after`` were acknowledged.

    The drive answers a whole chunk of lines at once, so right after an acknowledgement it is
    idle; the kill therefore comes ``phase`` seconds (busy-waited, a fraction of one line's
    EEPROM write) after the lines queued last, i.e. at a random point of the drive's work on
    them.  Returns (acknowledged, sent)."""
    port = serial.Serial(sim.path, 9600, timeout=0.005)
    sent = acked = 0
    buf = bytearray()
    deadline = time.monotonic() + 10
    try:
        while True:
            while sent < len(lines) and sent - acked < window:
                port.write(lines[sent].encode("ascii"))
                sent += 1
            if acked >= kill_after:
                break
            buf += port.read(max(1, port.in_waiting))
            acked = len(ACKED.findall(buf))
            assert b"\n*" not in buf, f"error message while streaming: {bytes(buf)!r}"
            assert time.monotonic() < deadline, f"only {acked} of {kill_after} acknowledgements: {bytes(buf)!r}"
        kill_at = time.perf_counter() + phase
        while time.perf_counter() < kill_at:
            pass
        sim.kill()
    finally:
        sim.kill()
        port.close()
    return acked, sent


def check_nvram_file(state_dir: Path) -> dict:
    data = json.loads((state_dir / "sers.nvram.json").read_text("utf-8"))
    assert isinstance(data, dict)
    return data


def write_config(tmp_path: Path) -> Path:
    config = tmp_path / "sers.yaml"
    config.write_text("address: 1\nboot_time: 0\n")
    return config


def test_kill_9_during_psave_keeps_a_written_value(tmp_path: Path) -> None:
    config = write_config(tmp_path)
    state = tmp_path / "state"
    rng = random.Random()
    kill_points = [rng.randint(1, 25) for _ in range(5)]
    expected: range | None = None  # values P1019 may have after the last kill
    for round_no in range(len(kill_points) + 1):
        sim = SimProcess(state, config)
        try:
            host = Host(sim.path)
            try:
                value = int(query(host, "P1019").removesuffix("U/min"))
            finally:
                host.close()
            if expected is None:
                assert value == 30  # factory default, nothing saved yet
            else:
                assert value in expected, f"P1019={value}, expected one of {expected} (kills {kill_points})"
                check_nvram_file(state)
            if round_no == len(kill_points):
                break
            base = 100 + 1000 * round_no
            values = list(range(base + 1, base + 61))
            lines = [f"#P1019={n} PSAVE\r" for n in values]
            acked, sent = stream_and_kill(sim, lines, kill_points[round_no], rng.uniform(0, 0.003))
            assert acked >= 1
            expected = range(values[acked - 1], values[sent - 1] + 1)
        finally:
            sim.kill()


def test_kill_9_during_program_download_leaves_old_or_prefix_of_new(tmp_path: Path) -> None:
    config = write_config(tmp_path)
    state = tmp_path / "state"
    rng = random.Random()
    kill_points = [0] + [rng.randint(1, 20) for _ in range(4)]
    old: list[str] = []
    written = False  # an acknowledged line has reached the EEPROM
    candidates: list[list[str]] = [[]]
    for round_no in range(len(kill_points) + 1):
        sim = SimProcess(state, config)
        try:
            host = Host(sim.path)
            try:
                rows = listing(host)
                assert [n for n, _ in rows] == list(range(1, len(rows) + 1)), rows
                program = [stmt for _, stmt in rows]
                assert program in candidates, (
                    f"after kill {round_no} at {kill_points}: listing {program} is neither the old program "
                    f"nor a prefix of the new one ({candidates[:1]} ... {candidates[-1:]})"
                )
                free = int(query(host, "P1122"))
                assert free == 1024 - sum(cost(s) for s in program) // 2
                if written:
                    check_nvram_file(state)
            finally:
                host.close()
            if round_no == len(kill_points):
                break
            old = program
            lines = ["#NEW\r"]
            statements: list[list[str]] = []
            for k in range(1, 31):
                line = [f"V={100 * round_no + k}"] if k % 3 else [f"W={k}", "E", f"O1={k % 2}"]
                statements.append(line)
                lines.append("#" + " ".join(line) + "\r")
            acked, sent = stream_and_kill(sim, lines, kill_points[round_no], rng.uniform(0, 0.003))
            written = written or acked > 0
            flat = [s for line in statements for s in line]
            done = sum(len(line) for line in statements[: max(0, acked - 1)])
            upto = sum(len(line) for line in statements[: max(0, sent - 1)])
            candidates = [flat[:m] for m in range(done, upto + 1)]
            if acked == 0:
                candidates.append(old)  # NEW may not have happened at all
        finally:
            sim.kill()


def test_t21_exact_rendering_with_full_decimals_and_units(sers: Plant) -> None:
    host = sers.host
    host.ask("#NEW\r")
    host.ask("#1 ON V=1000 W=5000 E\r")
    host.ask("#L1 O1=1 D=10 W=2000 E\r")
    host.ask("#QUIT\r")
    assert host.ask("#LIST\r") == (
        b"#LIST\r1: ON\n\r2: V=1000.0000\n\r3: W=5000.0000\n\r4: E\n\r5: L1\n\r6: O1=1\n\r7: D=10\n\r"
        b"8: W=2000.0000\n\r9: E\n\r\nok1\n\r"
    )
    host.ask("#P1028=7\r")  # numbers, units, indented (labels in column 1)
    assert host.ask("#LIST\r").startswith(
        "#LIST\r1:    ON\n\r2:    V=1000.0000U/min\n\r3:    W=5000.0000°\n\r4:    E\n\r5: L1\n\r".encode("latin-1")
    )


@pytest.mark.parametrize(("stored", "section"), [
    ({"1003": "abc"}, "params"),  # a string where a number belongs: failed every P1003 query
    ({"1011": 1.5}, "params"),  # a fraction in a bit mask: failed the device's creation
    ({"1001": [1]}, "params"),  # a list: failed the line's settings on every query
    ({"160": 99}, "params"),  # no weighting code: failed every weighted query
    ({"123": 0}, "params"),  # the feed constant is > 0: failed every weighted query
    ({"99999": 1}, "params"),  # no parameter at all
    ({"\u00b2": 1}, "params"),  # a superscript two, which str.isdigit takes: int() refused the whole file
    ({"\u0664\u0661": 100}, "params"),  # Arabic-Indic 41, which int() reads: was P41
    ({"1028": 1, "01028": 7}, "params"),  # a leading zero, which PSAVE never writes: a second P1028 (7 won)
    ({"47": "x"}, "registers"),  # W: failed arithmetic in a program
])
def test_a_stored_value_the_drive_never_stores_reads_as_a_checksum_error(
        plant_factory, tmp_path, capfd, stored: dict, section: str) -> None:
    """A hand-edited state file (fuzzed): before, the value went into RAM as it was and the
    drive failed later, in a query, a motion or at its creation.  Now the EEPROM fails its
    checksum as a damaged one does (display 7, factory values, spec §4.1) and stderr names the
    file; the program stored beside it stays."""
    image = {section: stored, "program": {"lines": [["V=100"], ["E"]]}}
    (tmp_path / "sers.nvram.json").write_text(json.dumps(image))
    plant = plant_factory({}, state_dir=tmp_path)
    host = plant.host
    assert plant.read("display") == {"char": "7", "blinking": False}
    assert query(host, "P1003") == "10U/min" and query(host, "W") == "0°"  # (factory values)
    assert query(host, "P51") == "0°"
    assert listing(host) == [(1, "V=100"), (2, "E")]
    assert f"devsim: memory {tmp_path / 'sers.nvram.json'}: " in capfd.readouterr().err


def test_a_stored_position_that_is_no_number_is_no_position(plant_factory, tmp_path) -> None:
    (tmp_path / "sers.nvram.json").write_text(json.dumps({"position": "nan"}))
    plant = plant_factory({}, state_dir=tmp_path)
    assert query(plant.host, "P51") == "0°"


def _drive_on(state_dir: Path, save: bool = True):
    """A drive on the memory file in ``state_dir`` (in-process, virtual time); with ``save`` its
    R0..R5 and W saved with its parameters (P1117=1, PSAVE): P1019=45 and W=500 stored."""
    from devsim.core.clock import VirtualClock
    from devsim.core.nvram import NonVolatileMemory
    from devsim.devices.sers.model import SersDrive

    nvram = NonVolatileMemory.for_device(state_dir, "sers", "sers")
    drive = SersDrive(clock=VirtualClock(), config={}, nvram=nvram)
    for number, value in ((1117, 1), (1019, 45), (47, 500), (1004, 2)) if save else ():
        drive.access.write_param(number, value)
    return drive, nvram


def _stored(state_dir: Path) -> tuple[float, float]:
    """P1019 and W as a drive powered on with the memory file reads them."""
    drive, nvram = _drive_on(state_dir, save=False)
    try:
        return drive.access.param_value(1019), drive.access.param_value(47)
    finally:
        nvram.close()


@pytest.mark.manual("§4.8.6.10", "P1117=1: PSAVE also stores R0..R5 and W")
@pytest.mark.parametrize("at", [1, 2])
def test_a_psave_with_p1117_killed_as_it_writes_leaves_the_parameters_and_registers_of_one_save(
        tmp_path: Path, at: int) -> None:
    """P1019 and W changed and saved again (PSAVE, P1117=1); the simulator is killed as it writes
    the file for the ``at``-th time: the file holds both values of the first save or both of the
    second.  (Before: the parameters and the registers were two writes, so a kill between them
    left P1019 of the second save with W of the first, an EEPROM no PSAVE wrote.)"""
    drive, nvram = _drive_on(tmp_path)
    try:
        drive.access.write_param(1019, 60)
        drive.access.write_param(47, 7)
        with killed_at_write(nvram, at) as writes:
            drive.access.write_param(1004, 2)
    finally:
        nvram.close()
    assert _stored(tmp_path) in ((45, 500), (60, 7))
    assert len(writes) == at or _stored(tmp_path) == (60, 7)  # (no kill: the save finished)


@pytest.mark.manual("§4.8.6.10", "P1004=3: the EEPROM back to factory defaults")
@pytest.mark.parametrize("at", [1, 2])
def test_factory_defaults_killed_as_they_are_written_leave_the_whole_save_or_none(tmp_path: Path, at: int) -> None:
    """P1004=3 after a PSAVE with P1117=1, the simulator killed as it writes the file for the
    ``at``-th time: the file holds the parameters and the registers, or neither.  (Before: two
    writes, the parameters deleted, then the registers: a kill between them left W of the save
    without its parameters.)"""
    drive, nvram = _drive_on(tmp_path)
    try:
        with killed_at_write(nvram, at) as writes:
            drive.access.write_param(1004, 3)
    finally:
        nvram.close()
    assert _stored(tmp_path) in ((45, 500), (30, 0))  # (30 U/min: P1019's factory value)
    assert len(writes) == at or _stored(tmp_path) == (30, 0)
