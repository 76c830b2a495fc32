"""Manual §4.7 (parameter overview) and §4.8.3.2 (status parameters) through the pty."""

from __future__ import annotations

import re

import pytest

from tests.sers.conftest import Plant
from tests.sers.test_programs import query

#: Parameters from the manual's "Liste aller Parameter" (§4.7), first rows.
LISTED = (0, 1, 2, 11, 12, 41, 42, 44, 47, 51, 76, 91, 100, 101, 102, 103, 108, 121, 122, 123, 134, 138, 147,
          160, 265, 336, 403, 1001, 1002, 1003, 1004)


@pytest.mark.manual("§4.7", "#listp sends a list of all parameters and their values")
def test_listp_lists_the_parameters_in_order(sers: Plant) -> None:
    answer = sers.host.ask("#LISTP\r").decode("latin-1")
    numbers = [int(n) for n in re.findall(r"\rP(\d+)=", "\r" + answer.replace("\n", ""))]
    assert numbers == sorted(numbers)
    readable = [n for n in LISTED if n not in (1004,)]  # (P1004 can only be written)
    assert set(readable) <= set(numbers)


@pytest.mark.manual("§4.7", "#P123=150 writes a parameter, acknowledged ok; #P123? answers 'P123=' value "
                    "(with its unit where it has one)")
def test_write_and_read_a_parameter(sers: Plant) -> None:
    host = sers.host
    assert host.ask("#P123=150\r") == b"#P123=150\r\nok1\n\r"
    assert query(host, "P123").startswith("150")
    assert query(host, "P41").endswith("U/min")


@pytest.mark.manual("§4.7", "a query of a parameter with a unit, such as the feed constant P123, sends the unit "
                    "with the value ('P123=150mm'); P123 is in the translational length unit (§4.8.4.7)")
@pytest.mark.parametrize(("weighting", "unit"), [(1, "mm"), (17, "in"), (2, "mm")])
def test_the_feed_constant_is_answered_with_its_unit(sers: Plant, weighting: int, unit: str) -> None:
    host = sers.host
    assert host.ask(f"#P76={weighting} P123=150\r").endswith(b"ok1\n\r")
    assert query(host, "P123") == f"150{unit}"
    assert host.ask("#P123=2.5\r").endswith(b"ok1\n\r")
    assert query(host, "P123") == f"2.5{unit}"


@pytest.mark.manual("§4.8.3.2", "P1013 bits: 1 right limit open (J3), 2 left limit open (J2), 4 STOP open (J4), "
                    "8 reference switch open (J1), 128 service switch open (J5)")
@pytest.mark.parametrize(("signal", "bit"), [("limit_right", 1), ("limit_left", 2), ("stop", 4)])
def test_p1013_bits(sers: Plant, signal: str, bit: int) -> None:
    host = sers.host
    base = int(query(host, "P1013"))
    assert base == 8 | 128  # reference switch and service switch open (not active)
    sers.set(f"input.{signal}", True)
    assert int(query(host, "P1013")) == base | bit


@pytest.mark.manual("§4.8.3.2", "P1013 bit 3 (8): reference switch open; bit 7 (128): service switch open")
def test_p1013_reference_and_service(sers: Plant) -> None:
    sers.set("input.reference", True)
    sers.set("input.service_ext", True)
    assert int(query(sers.host, "P1013")) == 0


@pytest.mark.manual("§4.6.1", "J1 reference switch, J2 left limit, J3 right limit, J4 STOP, J5 external service "
                    "switch in IF (IF J2=0: on the left limit switch)")
def test_j_bits_in_if(sers: Plant) -> None:
    host = sers.host
    sers.set("input.limit_left", True)
    sers.set("input.reference", True)
    from tests.sers.test_programs import download, finish, out, run

    host.ask("#P11=0\r")
    download(host, "IF J2=0 O1=1", "IF J1=1 O2=1", "IF J3=0 O3=1", "PE")
    run(host)
    finish(sers)
    assert (out(sers, 1), out(sers, 2), out(sers, 3)) == (True, True, False)


@pytest.mark.manual("§4.8.3.2", "P1042 (LP) = 1 if P51 < P1040 or P51 > P1041, else 0")
@pytest.mark.manual("§4.8.3.1", "errno 95 'Die negative Grenzposition ist größer als die positive'")
def test_lp(sers: Plant) -> None:
    host = sers.host
    assert query(host, "LP") == "0"
    assert host.ask("#P1041=100 P1040=10\r").endswith(b"ok1\n\r")
    assert query(host, "P1042") == "1"
    host.ask("#P51=20\r")
    assert query(host, "LP") == "0"


@pytest.mark.manual("§4.8.3.2", "P336 (POS) = 0 while the drive moves, 1 when it stands")
def test_pos_while_moving(sers: Plant) -> None:
    host = sers.host
    host.ask("#ON W=360 E\r")
    assert query(host, "POS") == "0"
    sers.settle()
    assert query(host, "P336") == "1"
