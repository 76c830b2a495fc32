"""Manual §4.3–§4.6 (program lines, labels, jumps) checked statement by statement through the pty.

Each test quotes the statement of the SERS manual (seed 003) it checks; the expected values come
from the manual, not from the simulator's output.
"""

from __future__ import annotations

import pytest

from tests.sers.conftest import Plant
from tests.sers.test_programs import download, finish, listing, normalise, out, query, refused, run


@pytest.mark.manual("§4.6.2", "Syntax: L dezimalkonstante - a value from 1 to 128 (L1 and L128 are labels)")
@pytest.mark.manual("§4.6.3", "GOTO label jumps to the label")
def test_labels_l1_and_l128_are_jump_targets(sers: Plant) -> None:
    host = sers.host
    download(host, "GOTO 128", "O1=1", "L128", "O2=1", "GOTO 1", "O3=1", "L1", "O4=1")
    run(host)
    finish(sers)
    # L128 skipped O1, GOTO 1 skipped O3
    assert (out(sers, 1), out(sers, 2), out(sers, 3), out(sers, 4)) == (False, True, False, True)


@pytest.mark.manual("§4.6.2", "a label number outside 1..128 is refused: errno 72 'Sprungziel ungültig' "
                    "(labels are jump targets)")
@pytest.mark.parametrize("label", ["L0", "L129", "L 200", "L999"])
def test_a_label_outside_1_to_128_is_refused_and_not_stored(sers: Plant, label: str) -> None:
    host = sers.host
    assert host.ask("#NEW\r").endswith(b"pgm\n\r")
    assert host.ask("#O1=1\r").endswith(b"pgm\n\r")
    refused(host, f"#O2=1 {label}\r", 72)
    host.ask("#QUIT\r")
    assert query(host, "P1137") == "72"
    assert listing(host) == ["O1=1"]  # the whole line was refused, the program kept


@pytest.mark.manual("§4.6.2", "a label number outside 1..128 is refused also in a direct line (errno 72)")
def test_a_label_outside_the_range_in_a_direct_line(sers: Plant) -> None:
    refused(sers.host, "#L129\r", 72)
    assert query(sers.host, "P1137") == "72"


@pytest.mark.manual("§4.3", "each statement gets its own line number: the lines '#1 ON V=1000 W=5000 E' and "
                    "'#O1=1 D=10 W=2000 E' are listed as '1: ...' and '5: ...' (P1028 with the user's line breaks)")
def test_line_numbering_with_the_users_line_breaks(sers: Plant) -> None:
    host = sers.host
    download(host, "ON V=1000 W=5000 E", "O1=1 D=10 W=2000 E")
    host.ask("#P1028=9\r")  # bit 0 numbers, bit 3 the user's line breaks (§4.8.5.4)
    answer = host.ask("#LIST\r").decode("latin-1")
    rows = answer.removeprefix("#LIST\r").removesuffix("\n\r\nok1\n\r").split("\n\r")
    # (the drive lists constants with their decimals, spec G-LIST: 'V=1000.0000' is 'V=1000')
    assert [normalise(row) for row in rows] == ["1: ON V=1000 W=5000 E", "5: O1=1 D=10 W=2000 E"]


@pytest.mark.manual("§4.3", "or (depending on P1028) one statement per row: 1: ON, 2: V=1000, ... 8: E")
def test_line_numbering_one_statement_per_row(sers: Plant) -> None:
    host = sers.host
    download(host, "ON V=1000 W=5000 E", "O1=1 D=10 W=2000 E")
    host.ask("#P1028=1\r")
    assert listing(host) == ["ON", "V=1000", "W=5000", "E", "O1=1", "D=10", "W=2000", "E"]
