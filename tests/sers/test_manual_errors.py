"""Manual §4.8.3.1 (drive errors, warnings, the errno list) and the refusals of parameter writes
(§4.7, §4.8) checked through the pty.

The errno of each refusal is the manual's (§4.8.3.1 "Liste der Fehlernummern"); the texts are the
manual's too (``errors.message``).
"""

from __future__ import annotations

import re

import pytest

from tests.sers.conftest import Plant
from tests.sers.test_programs import listing, query, refused


@pytest.mark.manual("§4.8.6.1", "P1034 'Darf nicht geändert werden - wird werkseitig eingestellt': a write is "
                    "refused with errno 12 'Zugriff verweigert' and the value stays")
def test_writing_the_factory_set_current_range_is_access_denied(sers: Plant) -> None:
    host = sers.host
    before = query(host, "P1034")
    refused(host, "#P1034=1\r", 12)
    assert query(host, "P1137") == "12"
    assert query(host, "P1034") == before


@pytest.mark.manual("§4.8.2.5", "P1133 firmware version: 'nur Lese-Parameter' - a write gets errno 105 "
                    "'Wert kann nicht geschrieben werden'")
@pytest.mark.manual("§4.8.3.2", "P1013 'kann nur gelesen werden' - a write gets errno 105")
@pytest.mark.parametrize("line", ["#P1133=1\r", "#P1013=0\r"])
def test_writing_a_read_only_parameter_is_errno_105(sers: Plant, line: str) -> None:
    refused(sers.host, line, 105)
    assert query(sers.host, "P1137") == "105"


@pytest.mark.manual("§4.8.4.1", "P1014 takes 0..3; another value is errno 80 'unbekannter Positioniermodus'")
@pytest.mark.manual("§4.8.2.1", "P0 takes 0, 1, 2; another value is errno 82 'ungültiger EEPROM Modus Wert'")
@pytest.mark.manual("§4.8.6.10", "P1004 takes 2..5; another value is errno 82 'ungültiger EEPROM Modus Wert'")
@pytest.mark.manual("§4.8.6.3", "P1031 takes 1, 2, 4, 8, 16; another value is errno 3 'ungültig'")
@pytest.mark.parametrize(("line", "errno"), [("#P1014=4\r", 80), ("#P0=3\r", 82), ("#P1004=7\r", 82),
                                             ("#P1004=1\r", 82), ("#P1031=3\r", 3), ("#P134=5\r", 3)])
def test_a_value_outside_the_choices_gets_the_rows_errno(sers: Plant, line: str, errno: int) -> None:
    refused(sers.host, line, errno)
    assert query(sers.host, "P1137") == str(errno)


@pytest.mark.manual("§4.8.3.1", "P12 value 16: an error message was generated, e.g. 'Parameterwert zu groß' "
                    "when a parameter is given an invalid value; P1137 holds its errno (1 'zu groß', 2 'zu klein')")
@pytest.mark.parametrize(("line", "errno"), [("#P1035=2\r", 1), ("#P1035=-1\r", 2)])
def test_a_value_out_of_range_is_too_large_or_too_small(sers: Plant, line: str, errno: int) -> None:
    host = sers.host
    refused(host, line, errno)
    assert query(host, "P1137") == str(errno)
    assert int(query(host, "P12")) & 16
    assert query(host, "P1035") == "1"  # the value stays (§4.8.6.4: 1 after power-on)


@pytest.mark.manual("§4.8.2.4", "P1136: on versions up to 6 A P1136 cannot be changed (errno 105); a 12 A "
                    "version takes P1136=1 (18 kHz)")
def test_p1136_only_on_a_12_a_version(plant_factory) -> None:
    small = plant_factory({"current_class": "06"})
    refused(small.host, "#P1136=1\r", 105)
    assert query(small.host, "P1136") == "0"
    large = plant_factory({"current_class": "12", "supply_class": "120"})
    assert large.host.ask("#P1136=1\r").endswith(b"ok1\n\r")
    assert query(large.host, "P1136") == "1"


@pytest.mark.manual("§4.8.6.1", "P1010 phase current in mA: 'der max. einstellbare Phasenstrom hängt von der "
                    "Version ab' - SERS 01 1400, 02 2800, 03 4200, 04 4000, 06 8400, 08 8400, 12 14500")
@pytest.mark.parametrize(("current_class", "maximum"), [("01", 1400), ("03", 4200), ("06", 8400), ("12", 14500)])
def test_the_phase_current_maximum_is_the_versions(plant_factory, current_class: str, maximum: int) -> None:
    host = plant_factory({"current_class": current_class}).host
    assert host.ask(f"#P1010={maximum}\r").endswith(b"ok1\n\r")
    refused(host, f"#P1010={maximum + 1}\r", 1)
    assert query(host, "P1010") == str(maximum)


# The manual's wording of errno 9 and 10 (§4.8.3.1), as the drive sends it (latin-1, spec G-ENC).
TOO_LARGE_CONSTANT = "\n*Dezimalkonstante zu groß\n\r".encode("latin-1")
RUN_TOO_SMALL = b"\n*run Dezimalkonstante zu klein\n\r"


@pytest.mark.manual("§4.6.1", "festkommakonstante: - 2147483.639 bis +2147483.639 (IF, WAIT and ':' compare "
                    "with it); §4.8.3.1 errno 10 'Dezimalkonstante zu groß'")
@pytest.mark.parametrize("line", ["#IF X>2147483.64\r", "#IF X>-2147483.640\r", "#WAIT X<99999999999\r",
                                  "#RS:X>3000000\r", "#IF V<>2147483640\r"])
def test_a_condition_constant_beyond_the_fixed_point_range_is_decimal_constant_too_large(
        sers: Plant, line: str) -> None:
    host = sers.host
    reply = host.ask(line)
    assert reply == line.encode("ascii") + b"\n" + TOO_LARGE_CONSTANT[1:], reply  # echo, then only the error
    assert query(host, "P1137") == "10"
    assert int(query(host, "P12")) & 16
    assert sers.read("motion.kind") is None  # the ':' jog did not start


@pytest.mark.manual("§4.6.1", "festkommakonstante: - 2147483.639 bis +2147483.639: the bounds themselves are taken")
@pytest.mark.parametrize("line", ["#IF X>2147483.639\r", "#IF X>-2147483.639\r", "#WAIT X<2147483.639\r"])
def test_a_condition_constant_at_the_bound_is_taken(sers: Plant, line: str) -> None:
    reply = sers.host.ask(line)
    assert re.fullmatch(rb".*\nok\d\n\r", reply, re.S) and b"*" not in reply, reply


@pytest.mark.manual("§4.6.10", "'Es können alle Parameter und 32-Bit Konstanten in Rechenoperationen verwendet "
                    "werden'; §4.8.3.1 errno 10 'Dezimalkonstante zu groß'")
@pytest.mark.parametrize("line", ["#X=1 -3000000\r", "#X=1 +2147483.64\r", "#X=1 /99999999999999\r"])
def test_a_calculation_constant_beyond_32_bits_is_decimal_constant_too_large(sers: Plant, line: str) -> None:
    host = sers.host
    assert host.ask(line).endswith(TOO_LARGE_CONSTANT)
    assert query(host, "P1137") == "10"
    assert query(host, "X") == "1"  # X=1 ran, the calculation did not


@pytest.mark.manual("§4.8.3.1", "errno 10 'Dezimalkonstante zu groß': a program line with such a constant is "
                    "refused, not stored")
def test_a_program_line_with_a_too_large_condition_constant_is_not_stored(sers: Plant) -> None:
    host = sers.host
    assert host.ask("#NEW\r").endswith(b"\npgm\n\r")
    assert host.ask("#L1 IF X>3000000\r").endswith(TOO_LARGE_CONSTANT)
    assert host.ask("#L1 IF X>300\r").endswith(b"\npgm\n\r")
    host.ask("#QUIT\r")
    assert listing(host) == ["L1", "IF X>300"]


@pytest.mark.manual("§4.8.3.1", "errno 9 'run Dezimalkonstante zu klein': RUN n starts at label n, and labels "
                    "run from L1 (§4.6.2: 'ein Wert von 1 bis 128')")
def test_run_0_is_run_decimal_constant_too_small(sers: Plant) -> None:
    host = sers.host
    assert host.ask("#NEW\r").endswith(b"\npgm\n\r")
    host.ask("#L1 X=5\r")
    host.ask("#QUIT\r")
    reply = host.ask("#RUN 0\r")
    assert reply == b"#RUN 0\r\n" + RUN_TOO_SMALL[1:], reply
    assert query(host, "P1137") == "9"
    assert query(host, "P0") == "0" and query(host, "X") == "0"  # the program did not start
    assert host.ask("#RUN 00\r").endswith(RUN_TOO_SMALL)


@pytest.mark.manual("§4.6.1", "IF: 'Es sind alle SERS-Parameter und digitalen Eingänge (I1 bis I16, und J1 bis J5) "
                    "erlaubt'; §4.8.3.1 errno 11 'unbekanntes if Ereignis'")
@pytest.mark.parametrize("line", ["#IF I17\r", "#IF J6\r", "#IF I0\r", "#WAIT J9\r", "#IF X=I17\r", "#RS:I0\r",
                                  "#IF J0=1\r"])
def test_a_condition_on_an_input_the_drive_does_not_have_is_an_unknown_if_event(sers: Plant, line: str) -> None:
    host = sers.host
    refused(host, line, 11)
    assert "\n*unbekanntes if Ereignis\n\r".encode("latin-1") in host.ask("#IF I20\r")  # the manual's wording
    assert query(host, "P1137") == "11"
    assert sers.read("motion.kind") is None  # the ':' jog did not start


@pytest.mark.manual("§4.6.1", "I1 bis I16, und J1 bis J5 are events of IF; elsewhere a missing input is no "
                    "parameter (errno 13 'Parameter nicht vorhanden')")
def test_the_inputs_a_condition_knows_are_taken_and_others_elsewhere_stay_errno_13(sers: Plant) -> None:
    host = sers.host
    for line in ("#IF I16\r", "#IF J5\r", "#IF I1=0\r", "#WAIT J1<>2\r"):
        reply = host.ask(line)
        assert re.fullmatch(rb".*\nok\d\n\r", reply, re.S) and b"*" not in reply, reply
    refused(host, "#X=I17\r", 13)
