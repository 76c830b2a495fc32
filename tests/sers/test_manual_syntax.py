"""Manual §4.2 "Syntax Definition": addresses (aliases), data, separators, operators and commands,
checked through the pty.  Expected values are the manual's equivalences, compared through the
drive's own answers (an alias and its P number answer the same value).
"""

from __future__ import annotations

import re

import pytest

from tests.sers.conftest import Plant
from tests.sers.test_programs import number, query

SECTION = "§4.2"


def _value(host, name: str) -> str:  # type: ignore[no-untyped-def]
    """The value text of ``name?`` without the unit."""
    match = re.match(r"-?[0-9.]+", query(host, name))
    assert match, name
    return match.group()


@pytest.mark.manual(SECTION, "addresses: A = P138, B = P1096, C1..C3 = P100..P102, M1..M3 = P1101..P1103, "
                    "V = P91, W = P47, X = P1047, Z = P1, O1..O4 = P1201..P1204")
@pytest.mark.parametrize(("alias", "number_", "value"), [
    ("A", 138, "250"), ("B", 1096, "300"), ("C1", 100, "7"), ("C2", 101, "8"), ("C3", 102, "9"),
    ("M1", 1101, "1"), ("M2", 1102, "1"), ("M3", 1103, "1"), ("V", 91, "123"), ("W", 47, "45.5"),
    ("X", 1047, "12.5"), ("Z", 1, "3"), ("O1", 1201, "1"), ("O4", 1204, "1"),
])
def test_an_alias_is_its_parameter(sers: Plant, alias: str, number_: int, value: str) -> None:
    host = sers.host
    assert host.ask(f"#{alias}={value}\r").endswith(b"ok1\n\r")
    assert float(_value(host, f"P{number_}")) == pytest.approx(float(value))
    back = "77" if alias in ("A", "B", "V") else "0"  # (A, B and V must stay above 0)
    assert host.ask(f"#P{number_}={back}\r").endswith(b"ok1\n\r")
    assert float(_value(host, alias)) == float(back)


@pytest.mark.manual(SECTION, "IN = P1300 (inputs I1..I8), POS = P336 (in position), ADC = P1046 (analog input)")
def test_read_only_aliases(sers: Plant) -> None:
    host = sers.host
    sers.set("input.I3", True)
    assert _value(host, "IN") == _value(host, "P1300") == "4"
    assert _value(host, "POS") == _value(host, "P336") == "1"
    assert _value(host, "ADC") == _value(host, "P1046")


@pytest.mark.manual(SECTION, "Dezimalkonstante: '.5' (= 0.5) and '10.75'; Datum: [-] Dezimalkonstante")
def test_decimal_constants(sers: Plant) -> None:
    host = sers.host
    host.ask("#W=.5\r")
    assert number(host, "W") == 0.5
    host.ask("#W=10.75\r")
    assert number(host, "W") == 10.75
    host.ask("#W=-10.75\r")
    assert number(host, "W") == -10.75


@pytest.mark.manual(SECTION, "Trennzeichen: space, comma, semicolon and TAB separate statements")
@pytest.mark.parametrize("separator", [" ", ",", ";", "\t"])
def test_separators(sers: Plant, separator: str) -> None:
    host = sers.host
    answer = host.ask(f"#V=321{separator}W=12\r")
    assert answer.endswith(b"ok1\n\r"), answer
    assert number(host, "V") == 321
    assert number(host, "W") == 12


@pytest.mark.manual(SECTION, "operators on the accumulator X: + - * / & | ^, and NOT (bitwise) and NEG")
@pytest.mark.parametrize(("line", "expected"), [
    ("X=6 +4", 10), ("X=6 -4", 2), ("X=6 /4", 1.5), ("X=6 &3", 2), ("X=6 |3", 7), ("X=6 ^3", 5),
    ("X=6 NEG", -6), ("X=6 NOT", ~6),
])
def test_accumulator_operators(sers: Plant, line: str, expected: float) -> None:
    host = sers.host
    assert host.ask(f"#{line}\r").endswith(b"ok1\n\r")
    assert number(host, "X") == expected


@pytest.mark.manual(SECTION, "'*' multiplies the accumulator; at the start of a line the drive's address must "
                    "precede it, or '*' is the broadcast address")
def test_multiplication_at_the_start_of_a_line_needs_the_address(sers: Plant) -> None:
    host = sers.host
    host.ask("#X=6\r")
    assert host.ask("#1*4\r").endswith(b"ok1\n\r")
    assert number(host, "X") == 24


@pytest.mark.manual(SECTION, "X = operand: the accumulator takes a parameter's value (X = V)")
def test_accumulator_takes_a_parameter(sers: Plant) -> None:
    host = sers.host
    host.ask("#V=250\r")
    host.ask("#X=V\r")
    assert number(host, "X") == 250
    host.ask("#V=X\r")
    assert number(host, "V") == 250


@pytest.mark.manual(SECTION, "Adresse ?? answers the parameter's designation")
@pytest.mark.parametrize(("name", "designation"), [("P91", "Geschwindigkeit - Positionieren"), ("P1134", "Drehrichtungsumkehr"),
                                                    ("P1137", "Letzte Fehlermeldungsnummer (errno)")])
def test_designation_query(sers: Plant, name: str, designation: str) -> None:
    answer = sers.host.ask(f"#{name}??\r").decode("latin-1")
    assert answer == f"#{name}??\r{designation}\n\r\nok1\n\r"


@pytest.mark.manual(SECTION, "// comment: all characters from here on are not interpreted")
def test_a_comment_ends_the_line(sers: Plant) -> None:
    host = sers.host
    assert host.ask("#V=111 // V=222 ON\r").endswith(b"ok1\n\r")
    assert number(host, "V") == 111
    assert sers.read("energized") is False


@pytest.mark.manual(SECTION, "ON is P134=7 (motor current on), OFF is P134=0")
def test_on_and_off_are_p134(sers: Plant) -> None:
    host = sers.host
    host.ask("#ON\r")
    assert query(host, "P134") == "7"
    host.ask("#OFF\r")
    assert query(host, "P134") == "0"
    host.ask("#P134=7\r")
    assert sers.read("energized") is True


@pytest.mark.manual(SECTION, "E starts the positioning job with the current W (P47), V (P91) and A (P138)")
@pytest.mark.manual(SECTION, "S stops the motor")
def test_e_and_s(sers: Plant) -> None:
    host = sers.host
    host.ask("#ON V=60 W=720 E\r")
    sers.advance(0.5)
    assert sers.read("motion.kind") == "position"
    host.ask("#S\r")
    sers.settle()
    assert 0 < number(host, "P51") < 720


@pytest.mark.manual("§4.1", "a faulty syntax is acknowledged at once with an error message introduced by '*'")
def test_a_latin_1_letter_is_no_statement(sers: Plant) -> None:
    """Byte DFh (``ß`` in latin-1) from garbage is no statement: the drive answers "Anweisung
    erwartet" as it comes and keeps moving; in programming mode nothing is stored.  (Before,
    Python's ``str.upper`` made it ``SS``: it ran as S, a stop, and NEW … QUIT stored it.)"""
    host = sers.host
    host.ask("#ON V=60 W=720 E\r")
    sers.advance(0.5)
    assert host.ask(b"#\xdf\r") == b"#\xdf\n*Anweisung erwartet\n\r\r"
    assert sers.read("motion.kind") == "position"
    host.ask("#NEW\r")
    host.ask(b"#\xdf\r")
    host.ask("#QUIT\r")
    assert sers.read("program") == []


@pytest.mark.parametrize("line", ['"€"', '"\udcff"'])
def test_a_program_line_the_serial_line_cannot_carry_is_refused(sers: Plant, line: str) -> None:
    """The control API's program holds only what a host could type on the line, a byte a character:
    '"€"' was stored (LIST showed '"?"'), and a lone surrogate (``devsim ctl set sers program`` with a
    byte that is no UTF-8 in its argument) was stored too, and with a state directory it failed the
    EEPROM file's write and left every later stored line raising UnicodeEncodeError on the port."""
    from devsim.core.points import BadValue

    with pytest.raises(BadValue, match="no character the drive's line carries"):
        sers.set("program", ["W=1", line])
    assert sers.read("program") == []
    host = sers.host
    assert host.ask("#PSAVE\r") == b"#PSAVE\r\nok1\n\r"
    for line in ("#NEW\r", "#W=1\r", "#QUIT\r"):
        host.ask(line)
    assert sers.read("program") == [["W=1"]]
