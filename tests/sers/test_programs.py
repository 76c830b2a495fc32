"""SERS sequence programs through a real pty, on virtual time (sers.md §3.5.9–§3.5.13, §4.2,
§4.4, §4.9, §4.10, T-10…T-13, T-15, T-16, T-18, T-20, T-21, §7 G-COUNTER, G-RETURN,
G-PROGEND, G-PARALLEL, G-TRACE, G-JOGPROG, G-D2; manual §4.5, §4.6, §4.8.5, §4.8.6.2).

Programs are downloaded the way a host does it (``#NEW`` … ``#QUIT``), started with ``#RUN``
or by inputs, and observed through queries, outputs and the axis position.  Polynomial moves
(T-14) and master mode (T-17) have their own files, test_polynomial.py and test_master.py.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import Any

import pytest

from tests.sers.conftest import Host, Plant

DEG = 12800 / 360  # motor increments per degree (default rotational weighting)
INC = 1 / DEG  # one increment in degrees: a move ends on the nearest increment
CYCLE = 0.0005  # one program statement per 0.5 ms (§1.2)
LIST_ROW = re.compile(r"(\d+): (.*)")


# ======================================================================================
# helpers
# ======================================================================================
def download(host: Host, *lines: str) -> None:
    """``#NEW``, one ``#<line>`` per line (each acknowledged with ``pgm``), ``#QUIT``."""
    assert host.ask("#NEW\r") == b"#NEW\r\npgm\n\r"
    for line in lines:
        answer = host.ask(f"#{line}\r")
        assert answer == f"#{line}\r\npgm\n\r".encode("latin-1"), f"line {line!r} refused: {answer!r}"
    assert host.ask("#QUIT\r").startswith(b"#QUIT\r\nok")


def run(host: Host, line: str = "#RUN\r") -> None:
    answer = host.ask(line)
    assert re.fullmatch(rb".*\r\nok[0-3]\n\r", answer, re.S), f"start refused: {answer!r}"


def query(host: Host, name: str) -> str:
    """``#<name>?`` → the value text of the answer, checking the framing."""
    answer = host.ask(f"#{name}?\r").decode("latin-1")
    match = re.fullmatch(rf"#{re.escape(name)}\?\r{re.escape(name.upper())}=(.*)\n\r\nok\d\n\r", answer)
    assert match, f"unexpected answer to {name}?: {answer!r}"
    return match.group(1)


def number(host: Host, name: str) -> float:
    """A queried value without its unit."""
    match = re.match(r"-?[0-9.]+", query(host, name))
    assert match
    return float(match.group())


def error_text(errno: int) -> str:
    from devsim.devices.sers.errors import message

    return message(errno)


def refused(host: Host, line: str, errno: int) -> None:
    """The line is answered with the error message of ``errno`` and no acknowledgement (a
    keyword such as ``NEW`` runs at its last character, so the message may precede the CR's
    echo, §3.2.4a)."""
    answer = host.ask(line).decode("latin-1")
    echo, _, after = answer.partition("\n*")
    if "\r" not in echo and not after.endswith("\n\r\r"):
        answer += host.port.read(1).decode("latin-1")  # the echo of the CR after the message
    assert f"\n*{error_text(errno)}\n\r" in answer, f"{line!r}: {answer!r}"
    assert not re.search(r"\n(ok\d|pgm)\n\r", answer), f"{line!r}: {answer!r}"


def normalise(statement: str) -> str:
    """``W=360.0000`` and ``W=360`` are the same stored constant (G-LIST decimals)."""
    return re.sub(r"(\d)\.0+\b", r"\1", statement.strip())


def listing(host: Host) -> list[str]:
    """``#LIST`` → the listed statements (numbers checked to run 1, 2, 3 …)."""
    answer = host.ask("#LIST\r").decode("latin-1")
    body = re.fullmatch(r"#LIST\r(.*?)\n(?:ok\d|pgm)\n\r", answer, re.S)
    assert body, answer
    rows = body.group(1).split("\n\r")
    assert rows[-1] == ""
    result = []
    for expected, row in enumerate(rows[:-1], start=1):
        match = LIST_ROW.fullmatch(row)
        assert match and int(match.group(1)) == expected, f"bad row {row!r} in {answer!r}"
        result.append(normalise(match.group(2)))
    return result


def dev(plant: Plant, name: str | None = None) -> Any:
    return plant.runtime.device(name or plant.name)


def until(plant: Plant, predicate: Callable[[Any], bool], timeout: float = 10.0) -> float:
    """Run virtual time until ``predicate(device)`` holds; returns the virtual time then."""
    device = dev(plant)
    assert plant.runtime.run_until(lambda: predicate(device), timeout), "condition never became true"
    return plant.runtime.now()


def out(plant: Plant, n: int) -> bool:
    return bool(plant.read(f"output.O{n}"))


def running(plant: Plant) -> bool:
    return plant.read("param.P0") == 1


def finish(plant: Plant, timeout: float = 30.0) -> float:
    """Run until the program has ended (P0=0); returns the virtual time."""
    return until(plant, lambda d: not d.model.interpreter.running, timeout)


def degrees(plant: Plant) -> float:
    return plant.read("axis.position") / DEG


def power_cycle(plant: Plant) -> None:
    plant.runtime.power_cycle(plant.name)
    plant.advance(2.0)  # display '-' for 2 s (§4.1)


# ======================================================================================
# T-10 counters (§4.6.1 example 3, §4.8.5.2, G-COUNTER)
# ======================================================================================
@pytest.mark.manual("§4.6.1", "IF C1>1: every IF on a counter counts it down by 1 (example 3 runs the block C1 times)")
@pytest.mark.manual("§4.8.5.2", "counters C1..C3 (P100..P102) for program loops")
@pytest.mark.parametrize("count", [10, 20])
def test_t10_counter_loop_runs_c1_times(sers: Plant, count: int) -> None:
    host = sers.host
    download(host, f"ON C1={count}", "L1", "WAIT I1=1", "WR=180 E", "IF C1>1 GT1", "PE")
    sers.set("input.I1", True)
    run(host)
    finish(sers, timeout=count * 1.0)
    assert degrees(sers) == pytest.approx(180 * count, abs=1e-3)
    assert query(host, "C1") == "0"  # the false test decrements too
    assert query(host, "P0") == "0"


@pytest.mark.manual("§4.6.8", "WAIT I1=1: the program waits until input I1 becomes 1")
def test_t10_counter_loop_waits_for_its_input_each_time(sers: Plant) -> None:
    host = sers.host
    download(host, "ON C1=3", "L1", "WAIT I1=1", "WR=180 E", "WAIT I1=0", "IF C1>1 GT1", "PE")
    run(host)
    for i in range(1, 4):
        sers.advance(0.5)
        assert degrees(sers) == pytest.approx(180 * (i - 1), abs=1e-3)  # WAIT I1=1 holds it
        sers.set("input.I1", True)
        sers.settle()
        sers.advance(0.01)
        sers.set("input.I1", False)
    finish(sers, 1.0)
    assert degrees(sers) == pytest.approx(540, abs=1e-3)


# ======================================================================================
# T-11 IF variants (§4.6.1)
# ======================================================================================
@pytest.mark.manual("§4.6.1", "IF without THEN: if the expression holds the next command runs, else it is skipped; the commands after it run either way (example 1)")
@pytest.mark.parametrize("warning", [False, True])
def test_t11_single_statement_if(sers: Plant, warning: bool) -> None:
    host = sers.host
    download(host, "IF P12<>0 O1=1", "GT 20", "O3=1", "L20", "O4=1", "PE")
    if warning:
        refused(host, "#V=20000\r", 122)  # an error message sets P12 value 16
        assert sers.read("P12") == 16
    run(host)
    finish(sers, 0.1)
    assert out(sers, 1) is warning
    assert out(sers, 3) is False  # GT 20 was executed either way
    assert out(sers, 4) is True


@pytest.mark.manual("§4.6.1", "whether the statement after the IF is on the same line or the next one makes no difference")
def test_t11_if_skips_the_next_statement_on_the_next_line(sers: Plant) -> None:
    host = sers.host
    download(host, "IF P12<>0", "O1=1", "O2=1", "PE")
    run(host)
    finish(sers, 0.1)
    assert (out(sers, 1), out(sers, 2)) == (False, True)


@pytest.mark.manual("§4.6.1", "IF ... THEN ... ELSE ... END: the THEN block if the expression holds, else the ELSE block (example 2)")
@pytest.mark.parametrize("warning", [False, True])
def test_t11_if_then_else_end(sers: Plant, warning: bool) -> None:
    host = sers.host
    download(host, "IF P12<>0 THEN", "O1=1 O2=0 O3=1", "ELSE", "O1=0 O2=1 O3=0", "END GT 20", "O4=1", "L20", "PE")
    if warning:
        refused(host, "#V=20000\r", 122)
    run(host)
    finish(sers, 0.1)
    expected = (True, False, True) if warning else (False, True, False)
    assert (out(sers, 1), out(sers, 2), out(sers, 3)) == expected
    assert out(sers, 4) is False


@pytest.mark.manual("§4.6.1", "the former syntax IF !expression is still accepted: '!' inverts the expression")
@pytest.mark.parametrize("i5", [False, True])
def test_t11_legacy_negated_if(sers: Plant, i5: bool) -> None:
    host = sers.host
    download(host, "IF !I5", "O1=1", "O2=1", "PE")
    sers.set("input.I5", i5)
    run(host)
    finish(sers, 0.1)
    assert out(sers, 1) is (not i5)
    assert out(sers, 2) is True


@pytest.mark.manual("§4.6.1", "a program read back from the SERS always shows the new syntax, also when the old one was written")
def test_t11_legacy_if_is_listed_in_the_new_syntax(sers: Plant) -> None:
    """§4.6.1: "Beim Auslesen … wird grundsätzlich die neue Syntax angezeigt"; T-11.3."""
    host = sers.host
    download(host, "IF !I5", "O1=1")
    assert listing(host) == ["IF I5=0", "O1=1"]


@pytest.mark.manual("§4.6.1", "example 4: IF ADC>R0 THEN X=ADC*1000 V=X WR=3600 E END")
def test_t11_if_then_with_adc(sers: Plant) -> None:
    host = sers.host
    download(host, "ON R0=0.2", "IF ADC>R0 THEN", "X=ADC*1000 V=X WR=3600 E", "END", "PE")
    sers.set("quantity.adc_volts", 2.5)
    assert sers.read("param.ADC") == pytest.approx(0.5)
    run(host)
    finish(sers, 30)
    assert number(host, "X") == pytest.approx(500)
    assert query(host, "V") == "500U/min"
    assert degrees(sers) == pytest.approx(3600, abs=1e-3)
    # below R0: the block is skipped
    sers.set("quantity.adc_volts", 0.5)
    run(host)
    finish(sers, 1)
    assert degrees(sers) == pytest.approx(3600, abs=1e-3)


# ======================================================================================
# T-12 arithmetic in a program (§4.6.10)
# ======================================================================================
@pytest.mark.manual("§4.6.10", "operations run left to right (no precedence) on the accumulator X; registers R0..R5")
def test_t12_arithmetic_in_a_program(sers: Plant) -> None:
    host = sers.host
    download(
        host,
        "V=1000 X=V*ADC+100 V=X",
        "W=2000 R0=4 R1=2 X=W+10000/R0*R1 R2=X",
        "W=360 X=W NEG W=X",
        "PE",
    )
    sers.set("quantity.adc_volts", 2.5)
    run(host)
    finish(sers, 0.1)
    assert query(host, "V") == "600U/min"
    assert number(host, "R2") == pytest.approx(6000)
    assert query(host, "W") == "-360°"


@pytest.mark.manual("§4.8.3.1", "P12 256: an arithmetic error in the program (errno 102 'Division durch 0'); P12 128 program error")
def test_t12_division_by_zero_is_a_program_error(sers: Plant) -> None:
    host = sers.host
    download(host, "X=5", "/0", "O1=1", "PE")
    run(host)
    finish(sers, 0.1)
    assert out(sers, 1) is False
    assert query(host, "P1137") == "102"
    assert sers.read("P12") == 16 | 128 | 256


# ======================================================================================
# T-13 delays (§4.8.5.1, G-D2)
# ======================================================================================
@pytest.mark.manual("§4.8.5.1", "D: a waiting time in tenths of a second")
@pytest.mark.parametrize(("p1141", "seconds"), [(0, 1.2), (1, 1.0)])
def test_t13_d_delay_with_p1141_factor(sers: Plant, p1141: int, seconds: float) -> None:
    host = sers.host
    host.ask(f"#P1141={p1141}\r")
    download(host, "O1=1", "D=10", "O2=1", "PE")
    run(host)
    t1 = until(sers, lambda d: d.read("output.O1"), 0.1)
    assert out(sers, 2) is False
    t2 = until(sers, lambda d: d.read("output.O2"), 5)
    assert t2 - t1 == pytest.approx(seconds, abs=0.002)


def test_t13_d2_timed_gosub_waits_for_the_move(sers: Plant) -> None:
    host = sers.host
    assert query(host, "P1110") == "1"
    download(host, "ON", "D2=10.0 GS60", "W=3600 E", "O1=1", "PE", "L60", "O2=1", "RT")
    run(host)
    t0 = sers.runtime.now()
    sers.advance(0.99)
    assert sers.read("param.DB") == 0
    sers.advance(0.02)
    assert sers.read("param.DB") == 1  # D2 in exact 0.1 s (no ×1.2)
    assert sers.read("motion.kind") == "position"  # the move started at once
    assert out(sers, 2) is False  # P1110=1: the jump waits for the positioning
    t_end = sers.runtime.now() + sers.settle()
    assert t_end - t0 > 2.0
    t_jump = until(sers, lambda d: d.read("output.O2"), 1)
    assert t_jump - t_end < 0.003  # directly after the move
    finish(sers, 1)
    assert out(sers, 1) is True  # RT came back to the statement after the move
    assert degrees(sers) == pytest.approx(3600, abs=1e-3)


def test_t13_d2_timed_goto_aborts_a_wait(sers: Plant) -> None:
    host = sers.host
    download(host, "D2=5 GT60", "WAIT I1=1", "O1=1", "PE", "L60", "O2=1", "PE")
    run(host)
    t0 = sers.runtime.now()
    t_jump = until(sers, lambda d: d.read("output.O2"), 2)
    assert t_jump - t0 == pytest.approx(0.5, abs=0.003)
    finish(sers, 0.1)
    assert out(sers, 1) is False  # the WAIT was abandoned, not completed


def test_t13_d2_sets_db_without_blocking(sers: Plant) -> None:
    host = sers.host
    download(host, "D2=10", "O1=1", "WAIT DB=1", "O2=1", "PE")
    run(host)
    t0 = sers.runtime.now()
    sers.advance(0.01)
    assert out(sers, 1) is True  # D2 does not block
    t2 = until(sers, lambda d: d.read("output.O2"), 2)
    assert t2 - t0 == pytest.approx(1.0, abs=0.003)


# ======================================================================================
# T-15 stand-alone program (§4.6.12)
# ======================================================================================
T15 = (
    "ON", "V=10", "W=25.5 E", "L1", "WAIT I2=0", "V=1500", "W=2000 E", "WAIT IN>7", "C1=10",
    "L2", "W=1000 E", "GOSUB10", "IF C1>1 GT2", "GOTO1", "L10", "O2=1", "W=5000 E", "O2=0",
    "RETURN",
)


@pytest.mark.manual("§4.6.12", "the stand-alone example program (endless loop with WAIT, C1 loop, GOSUB10) in mode RELATIV LÖSCHEN")
@pytest.mark.manual("§3.6.4", "stand-alone operation: the SERS runs its EEPROM program as an independent sequence control")
def test_t15_stand_alone_example(plant_factory) -> None:
    plant = plant_factory({"params": {"P1014": 1}})
    host = plant.host
    download(host, *T15)
    plant.set("input.I2", True)  # hold the program at WAIT I2=0 after the first move
    run(host)
    until(plant, lambda d: d.model.interpreter.waiting == "wait" and d.model.motion.kind is None, 10)
    assert degrees(plant) == pytest.approx(25.5, abs=INC)
    start = plant.read("axis.position")
    plant.set("input.I4", True)  # IN=8 > 7
    plant.set("input.I2", False)
    plant.advance(0.01)
    plant.set("input.I2", True)  # the next outer cycle stops at WAIT I2=0 again
    for _ in range(10):
        until(plant, lambda d: d.read("output.O2"), 10)
        rise = plant.read("axis.position")
        until(plant, lambda d: d.model.motion.kind == "position", 0.01)
        assert out(plant, 2) is True  # O2 is high during the 5000° move ...
        plant.settle()
        assert out(plant, 2) is True  # ... until it has ended
        until(plant, lambda d: not d.read("output.O2"), 0.01)
        assert (plant.read("axis.position") - rise) / DEG == pytest.approx(5000, abs=INC)
    until(plant, lambda d: d.model.interpreter.waiting == "wait" and d.model.motion.kind is None, 10)
    assert (plant.read("axis.position") - start) / DEG == pytest.approx(2000 + 10 * 6000, abs=21 * INC)
    assert running(plant)  # an endless loop


# ======================================================================================
# T-16 parallel (BCD) mode (§4.5.2, §4.6.12, G-PARALLEL)
# ======================================================================================
@pytest.mark.manual("§4.6.12", "the parallel-mode example: L1 ON RT, L2 V=1000 W=2500 E RT, L3 ..., L4 ... RETURN for the addresses 0..3")
@pytest.mark.manual("§4.5.2", "parallel mode: an edge on the start input I8 calls the label of the BCD address on the inputs (address 0 -> L1) and runs to the next RT")
@pytest.mark.manual("§3.6.3", "parallel (BCD) mode: subroutines in the EEPROM are called through the digital inputs")
def test_t16_parallel_bcd_example(plant_factory) -> None:
    plant = plant_factory({"params": {"P1022": 3, "P1021": 128}})
    host = plant.host
    download(host, "L1 ON RT", "L2 V=1000 W=2500 E RT", "L3 V=10 W=10.5 E RT", "L4", "V=20.8", "W=40.6", "E",
             "RETURN")
    host.ask("#ON\r")
    plant.set("input.I1", True)
    plant.set("input.I2", True)
    plant.set("input.I8", True)  # start edge: address 3 → L4
    plant.advance(0.01)
    assert plant.read("motion.kind") == "position"
    assert running(plant)
    plant.settle()
    plant.advance(0.01)
    assert not running(plant)  # RETURN ends the subroutine; the dispatcher waits again
    assert query(host, "V") == "20.8U/min"
    assert query(host, "W") == "40.6°"
    assert degrees(plant) == pytest.approx(40.6, abs=INC)
    # no inputs, new edge on I8 → L1 (address 0): ON
    host.ask("#OFF\r")
    plant.set("input.I1", False)
    plant.set("input.I2", False)
    plant.advance(0.01)
    assert plant.read("energized") is False  # releasing the address lines starts nothing
    plant.set("input.I8", False)
    plant.advance(0.01)
    plant.set("input.I8", True)
    plant.advance(0.01)
    assert plant.read("energized") is True
    assert degrees(plant) == pytest.approx(40.6, abs=INC)  # only L1 ran
    assert not running(plant)


# ======================================================================================
# T-18 event-driven mode (§4.5.2, P1098)
# ======================================================================================
EVENT_PROGRAM = ("L1 X=R0*10+1 R0=X D=2 RT", "L3 X=R0*10+3 R0=X D=2 RT")


@pytest.fixture
def events(plant_factory) -> Plant:
    plant: Plant = plant_factory({"params": {"P1098": 5}})
    download(plant.host, *EVENT_PROGRAM)
    return plant


def log(plant: Plant) -> str:
    return str(int(plant.read("param.R0")))


@pytest.mark.manual("§4.5.2", "event-driven mode: a rising edge on an input enabled in P1098 starts its subroutine Ln when no program runs (P0=0)")
def test_t18_edges_start_their_subroutines(events: Plant) -> None:
    events.set("input.I1", True)
    events.advance(0.01)
    assert running(events)
    events.advance(1.0)
    assert log(events) == "1"
    assert not running(events)
    events.set("input.I3", True)
    events.advance(1.0)
    assert log(events) == "13"
    events.set("input.I2", True)  # not enabled in P1098
    events.advance(1.0)
    assert log(events) == "13"


@pytest.mark.manual("§4.5.2", "several inputs active at once: I1 has the highest priority, then I2 ...; all active inputs' programs run one after the other")
def test_t18_simultaneous_edges_run_l1_then_l3(events: Plant) -> None:
    events.set("input.I1", True)
    events.set("input.I3", True)
    events.advance(2.0)
    assert log(events) == "13"


def test_t18_simultaneous_edges_priority_does_not_depend_on_set_order(events: Plant) -> None:
    """Edges within the same 0.5 ms cycle are simultaneous: I1 has the highest priority."""
    events.set("input.I3", True)
    events.set("input.I1", True)
    events.advance(2.0)
    assert log(events) == "13"


@pytest.mark.manual("§4.5.2", "an input that becomes inactive while a program runs starts nothing: edges are not stored")
def test_t18_edge_that_ends_during_a_program_is_not_stored(events: Plant) -> None:
    events.set("input.I1", True)
    events.advance(0.05)
    assert running(events)
    events.set("input.I3", True)
    events.advance(0.05)
    events.set("input.I3", False)  # gone before L1 finishes
    events.advance(2.0)
    assert log(events) == "1"
    assert not running(events)


# ======================================================================================
# T-20 programming mode + RUN (§4.5.3)
# ======================================================================================
@pytest.mark.manual("§4.5.3", "NEW starts programming mode deleting the program, PGM edits it; each line is acknowledged 'pgm'")
@pytest.mark.manual("§4.8.2.1", "P0=1 / RUN starts the EEPROM program; P0 reads 1 while it runs")
def test_t20_programming_mode_and_run(sers: Plant) -> None:
    host = sers.host
    assert host.ask("#NEW\r") == b"#NEW\r\npgm\n\r"
    assert host.ask("#ON\r") == b"#ON\r\npgm\n\r"
    assert host.ask("#W=360 E\r") == b"#W=360 E\r\npgm\n\r"
    assert sers.read("energized") is False
    assert host.ask("#LIST\r") == b"#LIST\r1: ON\n\r2: W=360.0000\n\r3: E\n\r\npgm\n\r"
    assert host.ask("#QUIT\r") == b"#QUIT\r\nok1\n\r"
    assert host.ask("#RUN\r") == b"#RUN\r\nok1\n\r"
    sers.advance(0.01)
    assert sers.read("energized") is True
    assert sers.read("motion.kind") == "position"
    finish(sers, 10)
    assert degrees(sers) == pytest.approx(360, abs=1e-3)
    assert query(host, "P0") == "0"


# ======================================================================================
# program errors and program end (§4.4.2, §4.4.3, G-RETURN, G-PROGEND)
# ======================================================================================
NESTED = ("GS1", "O1=1", "PE", "L1 GS2 RT", "L2 GS3 RT", "L3 GS4 RT", "L4 O2=1 GS5 RT", "L5 O3=1 RT")


@pytest.mark.manual("§4.4", "subroutine nesting depth at most 4")
def test_gosub_nesting_of_four_is_allowed(sers: Plant) -> None:
    host = sers.host
    download(host, *NESTED[:6], "L4 O2=1 RT")
    run(host)
    finish(sers, 0.1)
    assert (out(sers, 1), out(sers, 2)) == (True, True)
    assert sers.read("P12") == 0


@pytest.mark.manual("§4.4", "subroutine nesting deeper than 4 is refused (errno 73 'Stack Überlauf')")
def test_gosub_nesting_over_four_is_a_stack_overflow(sers: Plant) -> None:
    host = sers.host
    download(host, *NESTED)
    run(host)
    finish(sers, 0.1)
    assert out(sers, 2) is True
    assert out(sers, 3) is False  # the fifth GOSUB failed
    assert out(sers, 1) is False
    assert query(host, "P1137") == "73"
    assert sers.read("P12") == 16 | 128
    assert sers.read("display") == {"char": "H", "blinking": True}
    assert host.ask("#\r") == b"#\r\nok3\n\r"


@pytest.mark.manual("§4.8.3.1", "P12 16 'Sprungziel existiert nicht' at GOTO/GOSUB to a label that does not exist in the program (errno 71)")
def test_goto_to_a_missing_label_is_errno_71(sers: Plant) -> None:
    host = sers.host
    download(host, "O1=1", "GT 99", "O2=1")
    run(host)
    finish(sers, 0.1)
    assert (out(sers, 1), out(sers, 2)) == (True, False)
    assert query(host, "P1137") == "71"
    assert sers.read("P12") == 16 | 128
    assert sers.read("display") == {"char": "H", "blinking": True}


def test_return_without_gosub_from_line_1_is_errno_72(sers: Plant) -> None:
    host = sers.host
    download(host, "O1=1", "RT", "O2=1")
    run(host)
    finish(sers, 0.1)
    assert (out(sers, 1), out(sers, 2)) == (True, False)
    assert query(host, "P1137") == "72"
    assert sers.read("P12") == 16 | 128


def test_run_n_subroutine_ends_normally_at_return(sers: Plant) -> None:
    host = sers.host
    download(host, "O1=1", "PE", "L5", "O2=1", "RT", "O3=1")
    run(host, "#RUN 5\r")
    finish(sers, 0.1)
    assert (out(sers, 1), out(sers, 2), out(sers, 3)) == (False, True, False)
    assert sers.read("P12") == 0


@pytest.mark.manual("§4.2", "PE: end of program")
def test_pe_ends_the_program(sers: Plant) -> None:
    host = sers.host
    download(host, "O1=1", "PE", "O2=1")
    run(host)
    assert query(host, "P0") == "1"
    finish(sers, 0.1)
    assert query(host, "P0") == "0"
    assert (out(sers, 1), out(sers, 2)) == (True, False)
    assert sers.read("P12") == 0


def test_end_of_program_ends_it(sers: Plant) -> None:
    host = sers.host
    download(host, "O1=1", "O2=1")
    run(host)
    sers.advance(0.01)
    assert query(host, "P0") == "0"
    assert (out(sers, 1), out(sers, 2)) == (True, True)
    assert sers.read("P12") == 0


@pytest.mark.manual("§4.8.3.2", "P1129=1: at the end of a program '@nP0=0' is sent")
def test_p1129_reports_the_end_of_the_program(plant_factory) -> None:
    plant = plant_factory({"address": 2, "params": {"P1129": 1}})
    host = plant.host
    download(host, "ON W=36 E", "PE")
    run(host)
    finish(plant, 5)
    host.expect(b"@2P0=0\n\r")
    assert host.ask("#P0?\r") == b"#P0?\rP0=0\n\r\nok1\n\r"  # nothing else was sent


def test_no_p0_message_without_p1129(sers: Plant) -> None:
    host = sers.host
    download(host, "O1=1", "PE")
    run(host)
    finish(sers, 0.1)
    assert host.ask("#P0?\r") == b"#P0?\rP0=0\n\r\nok1\n\r"


@pytest.mark.parametrize(("p1126", "port", "while_running"), [(2, 2, True), (-3, 3, False)])
def test_p1126_output_while_running(sers: Plant, p1126: int, port: int, while_running: bool) -> None:
    host = sers.host
    host.ask(f"#P1126={p1126}\r")
    download(host, "D=1", "PE")
    assert out(sers, port) is not while_running
    run(host)
    assert out(sers, port) is while_running
    finish(sers, 1)
    assert out(sers, port) is not while_running


# ======================================================================================
# stop and continuation, P1033 (§4.4.4, manual §4.8.6.2)
# ======================================================================================
STOP_PROGRAM = ("ON", "WR=3600 E", "O1=1", "PE", "L65", "X=R0+1 R0=X", "O4=1", "WAIT I1=1", "PE")


def stopped(plant: Plant, after: float = 1.0) -> float:
    """Let the program's move run ``after`` s, stop it with ``#S``; returns P51 at rest."""
    plant.advance(after)
    assert plant.read("motion.kind") == "position"
    assert plant.host.ask("#S\r").startswith(b"#S\r\nok")
    plant.settle()
    return degrees(plant)


@pytest.mark.manual("§4.8.6.2", "P1033=0: after a stop the program starts again from the beginning")
def test_p1033_0_restarts_at_line_1(sers: Plant) -> None:
    host = sers.host
    download(host, *STOP_PROGRAM[:4])
    run(host)
    at = stopped(sers)
    assert 0 < at < 3600
    assert query(host, "P0") == "0"
    assert out(sers, 1) is False
    run(host)
    finish(sers, 20)
    assert degrees(sers) == pytest.approx(at + 3600, abs=1e-3)  # the whole W anew
    assert out(sers, 1) is True


@pytest.mark.manual("§4.8.6.2", "P1033=1: after a stop the program continues where it was stopped")
def test_p1033_1_continues_the_interrupted_move(sers: Plant) -> None:
    host = sers.host
    host.ask("#P1033=1\r")
    download(host, *STOP_PROGRAM[:4])
    run(host)
    at = stopped(sers)
    assert 0 < at < 3600
    assert query(host, "P0") == "0"
    run(host)
    finish(sers, 20)
    assert degrees(sers) == pytest.approx(3600, abs=1e-3)  # only the remaining distance
    assert out(sers, 1) is True  # and the program went on after the move


def test_p1033_1_two_stops_restart(sers: Plant) -> None:
    host = sers.host
    host.ask("#P1033=1\r")
    download(host, *STOP_PROGRAM[:4])
    run(host)
    stopped(sers)
    run(host)
    at = stopped(sers, 0.5)
    run(host)
    finish(sers, 20)
    assert degrees(sers) == pytest.approx(at + 3600, abs=1e-3)
    assert out(sers, 1) is True


def test_p1033_1_continues_a_wait(sers: Plant) -> None:
    host = sers.host
    host.ask("#P1033=1\r")
    download(host, "O1=1", "WAIT I1=1", "O2=1", "PE")
    run(host)
    sers.advance(0.1)
    host.ask("#S\r")
    assert query(host, "P0") == "0"
    run(host)
    sers.advance(0.1)
    assert running(sers)  # still waiting for I1
    assert out(sers, 2) is False
    sers.set("input.I1", True)
    finish(sers, 0.1)
    assert out(sers, 2) is True


def test_p1033_1_continues_an_interrupted_jog_until_condition(sers: Plant) -> None:
    host = sers.host
    host.ask("#P1033=1\r")
    download(host, "ON", "RS:I1=1", "O1=1", "PE")
    run(host)
    sers.advance(0.5)
    host.ask("#S\r")
    sers.settle()
    run(host)
    sers.advance(0.5)
    assert sers.read("motion.kind") == "jog"  # jogging again until I1
    sers.set("input.I1", True)
    sers.settle()
    finish(sers, 0.1)
    assert out(sers, 1) is True


@pytest.mark.manual("§4.6.2", "P1033=2: label L65 is jumped to when a program ends unexpectedly, e.g. by an external stop")
def test_p1033_2_stop_jumps_to_l65(sers: Plant) -> None:
    host = sers.host
    host.ask("#P1033=2\r")
    download(host, *STOP_PROGRAM)
    run(host)
    stopped(sers)
    sers.advance(0.01)
    assert running(sers)
    assert out(sers, 4) is True
    assert out(sers, 1) is False
    assert query(host, "P1118") == "1"


@pytest.mark.manual("§4.6.2", "without label L65 the program ends")
def test_p1033_2_without_l65_stops(sers: Plant) -> None:
    host = sers.host
    host.ask("#P1033=2\r")
    download(host, *STOP_PROGRAM[:4])
    run(host)
    stopped(sers)
    sers.advance(0.01)
    assert not running(sers)
    assert out(sers, 1) is False


def test_p1033_3_l65_only_once_until_p1118_is_cleared(sers: Plant) -> None:
    host = sers.host
    host.ask("#P1033=3\r")
    download(host, *STOP_PROGRAM)
    run(host)
    stopped(sers)
    sers.advance(0.01)
    assert log(sers) == "1"
    # a drive error during the L65 handling neither stops the program nor re-enters L65
    sers.set("quantity.heatsink_temperature", 90.0)
    sers.advance(0.2)
    assert sers.read("P11") == 2
    assert running(sers)
    assert log(sers) == "1"
    assert host.ask("#P1118=0\r").startswith(b"#P1118=0\r\nok")
    sers.set("input.limit_right", True)  # a new error: L65 may be entered again
    sers.advance(0.01)
    assert running(sers)
    assert log(sers) == "2"


@pytest.mark.manual("§4.6.2", "P1033=2: L65 is also jumped to on a drive error")
def test_drive_error_with_p1033_2_runs_l65(sers: Plant) -> None:
    host = sers.host
    host.ask("#P1033=2\r")
    download(host, *STOP_PROGRAM)
    run(host)
    sers.advance(1.0)
    sers.set("input.limit_right", True)
    sers.advance(0.5)
    assert sers.read("P11") == 8192
    assert running(sers)
    assert out(sers, 4) is True
    assert out(sers, 1) is False


def test_drive_error_with_p1033_0_stops_the_program(sers: Plant) -> None:
    host = sers.host
    download(host, *STOP_PROGRAM)
    run(host)
    sers.advance(1.0)
    sers.set("input.limit_right", True)
    sers.advance(0.5)
    assert not running(sers)
    assert out(sers, 4) is False


# ======================================================================================
# starting: autostart, start input, refusals (§4.1, §4.4.1)
# ======================================================================================
@pytest.mark.manual("§3.1.2", "DIP switch 2 bit 8 ON: a valid EEPROM program starts automatically after a power-on reset")
def test_autostart_after_power_cycle(plant_factory, tmp_path) -> None:
    plant = plant_factory({"autostart": True}, state_dir=tmp_path)
    host = plant.host
    download(host, "O2=1", "WAIT I1=1", "PE")
    assert not running(plant)
    plant.runtime.power_cycle(plant.name)
    plant.advance(1.9)
    assert not running(plant)  # still initialising
    plant.advance(0.1 + 0.01)
    assert running(plant)
    assert out(plant, 2) is True


def test_autostart_with_a_program_from_the_config_state(plant_factory, tmp_path) -> None:
    plant = plant_factory({"autostart": True}, state_dir=tmp_path)
    plant.runtime.call(lambda: dev(plant).apply_state({"program": ["O3=1 PE"]}))
    power_cycle(plant)
    plant.advance(0.01)
    assert out(plant, 3) is True
    assert listing(plant.host) == ["O3=1", "PE"]


@pytest.mark.manual("§3.1.4", "service switch ON: no autostart and no program start over the interface")
def test_no_autostart_with_the_service_switch(plant_factory, tmp_path) -> None:
    plant = plant_factory({"autostart": True, "service_switch": True}, state_dir=tmp_path)
    download(plant.host, "O2=1", "PE")
    power_cycle(plant)
    plant.advance(0.1)
    assert out(plant, 2) is False


COUNT_PROGRAM = ("X=R0+1 R0=X", "D=1", "PE")


@pytest.mark.manual("§4.8.1.1", "P1023=0: the program starts on an edge at the start input I8")
def test_start_input_edge(plant_factory) -> None:
    plant = plant_factory({"params": {"P1021": 128, "P1023": 0}})
    download(plant.host, *COUNT_PROGRAM)
    plant.set("input.I8", True)
    plant.advance(1.0)
    assert log(plant) == "1"  # one edge, one start
    plant.set("input.I8", False)
    plant.advance(0.1)
    plant.set("input.I8", True)
    plant.advance(0.5)
    assert log(plant) == "2"


@pytest.mark.manual("§4.8.1.1", "P1023=1: the program starts while the start input I8 is set (static)")
def test_start_input_level(plant_factory) -> None:
    plant = plant_factory({"params": {"P1021": 128, "P1023": 1}})
    download(plant.host, *COUNT_PROGRAM)
    plant.set("input.I8", True)
    plant.advance(1.0)
    runs = int(log(plant))
    assert runs >= 7  # restarted while the level stays (0.12 s per run)
    plant.set("input.I8", False)
    plant.advance(1.0)
    assert int(log(plant)) == runs + 1 or int(log(plant)) == runs


@pytest.mark.manual("§3.3.1", "'Start Programm' on I8 can only be enabled through P1021 (value 128)")
def test_start_input_needs_p1021_128(sers: Plant) -> None:
    download(sers.host, *COUNT_PROGRAM)
    sers.set("input.I8", True)
    sers.advance(0.5)
    assert log(sers) == "0"


@pytest.mark.manual("§4.8.3.1", "errno 65 'Programmstart nicht möglich wenn Serviceschalter an ist'")
def test_run_refused_with_the_service_switch(plant_factory) -> None:
    plant = plant_factory({"service_switch": True})
    download(plant.host, "O1=1", "PE")
    refused(plant.host, "#RUN\r", 65)
    assert query(plant.host, "P1137") == "65"
    plant.advance(0.1)
    assert out(plant, 1) is False


@pytest.mark.manual("§4.8.3.1", "errno 66 'Programmstart nicht möglich, Zustandsklasse-1 Fehler'")
def test_run_refused_with_a_drive_error(sers: Plant) -> None:
    download(sers.host, "O1=1", "PE")
    sers.set("input.limit_right", True)
    refused(sers.host, "#RUN\r", 66)
    sers.advance(0.1)
    assert out(sers, 1) is False


def test_run_n_and_p0_1(sers: Plant) -> None:
    host = sers.host
    download(host, "O1=1", "PE", "L5 O2=1 RT")
    refused(host, "#RUN 7\r", 71)  # no such label
    refused(host, "#RUN 200\r", 72)  # not a label number
    assert not running(sers)
    run(host, "#P0=1\r")  # = RUN
    finish(sers, 0.1)
    assert (out(sers, 1), out(sers, 2)) == (True, False)


@pytest.mark.manual("§4.8.3.1", "errno 69 'kein gültiges Programm vorhanden'")
def test_run_refused_without_a_program(sers: Plant) -> None:
    refused(sers.host, "#RUN\r", 69)
    sers.host.ask("#NEW\r")
    sers.host.ask("#QUIT\r")
    refused(sers.host, "#RUN\r", 69)


@pytest.mark.manual("§4.5.3", "for programming mode the SERS must be stopped (errno 44 'Programm läuft noch')")
@pytest.mark.parametrize("line", ["#NEW\r", "#PGM\r", "#RUN\r", "#P0=2\r"])
def test_refused_while_a_program_runs(sers: Plant, line: str) -> None:
    host = sers.host
    download(host, "O1=1", "WAIT I1=1", "PE")
    run(host)
    sers.advance(0.01)
    refused(host, line, 44)
    assert running(sers)
    assert listing(host) == ["O1=1", "WAIT I1=1", "PE"]


# ======================================================================================
# the program and the serial interface share the drive (§1.2)
# ======================================================================================
def test_endless_program_does_not_starve_the_serial_interface(sers: Plant) -> None:
    host = sers.host
    download(host, "L1 X=X+1 GT1")
    run(host)
    sers.advance(0.1)
    x1 = number(host, "X")
    assert 40 <= x1 <= 70  # 4 statements per round at 0.5 ms each
    assert query(host, "P0") == "1"
    sers.advance(0.1)
    assert number(host, "X") > x1
    assert host.ask("#S\r") == b"#S\r\nok1\n\r"
    x2 = number(host, "X")
    sers.advance(0.1)
    assert number(host, "X") == x2
    assert query(host, "P0") == "0"


@pytest.mark.manual("§4.8.6.10", "P1127=1: programs run 500 statements per second (2 ms cycle); P1127=0: 500 µs")
@pytest.mark.parametrize(("p1127", "cycle"), [(0, 0.0005), (1, 0.002)])
def test_p1127_sets_the_statement_time(sers: Plant, p1127: int, cycle: float) -> None:
    host = sers.host
    host.ask(f"#P1127={p1127}\r")
    download(host, "O1=1", "O2=1", "O3=1", "O4=1", "PE")
    run(host)
    t0 = sers.runtime.now()
    t1 = until(sers, lambda d: d.read("output.O1"), 1)
    t4 = until(sers, lambda d: d.read("output.O4"), 1)
    assert t4 - t1 == pytest.approx(3 * cycle, abs=1e-6)
    assert t1 - t0 <= cycle + 1e-6


# ======================================================================================
# jog statements in a program (§4.6.9, G-JOGPROG)
# ======================================================================================
@pytest.mark.manual("§4.6.9", "RS:I1=1 jogs right slow (P1019) until I1 is set, then brakes at once with P1018 to standstill")
def test_jog_until_condition_blocks_until_standstill(sers: Plant) -> None:
    host = sers.host
    download(host, "ON", "RS:I1=1", "O1=1", "PE")
    run(host)
    sers.advance(1.0)
    assert sers.read("motion.kind") == "jog"
    assert sers.read("axis.velocity") > 0
    assert out(sers, 1) is False
    sers.set("input.I1", True)
    sers.advance(0.001)
    assert sers.read("motion.kind") is not None
    assert out(sers, 1) is False  # still braking
    sers.settle()
    until(sers, lambda d: d.read("output.O1"), 0.01)
    assert not sers.read("axis.moving")


@pytest.mark.manual("§4.6.9", "with P1039 != 0 the drive travels the overrun distance P1039 (braking included) after the event")
def test_jog_until_condition_with_overrun_distance(sers: Plant) -> None:
    host = sers.host
    host.ask("#P1039=90\r")
    download(host, "ON", "RS:I1=1", "O1=1", "PE")
    run(host)
    sers.advance(1.0)
    sers.set("input.I1", True)
    at = degrees(sers)
    sers.settle()
    assert degrees(sers) - at == pytest.approx(90, abs=0.01)  # the overrun includes braking
    finish(sers, 0.1)
    assert out(sers, 1) is True


def test_plain_jog_in_a_program_continues_at_once(sers: Plant) -> None:
    host = sers.host
    download(host, "ON", "RS", "O1=1", "PE")
    run(host)
    finish(sers, 0.1)
    assert out(sers, 1) is True
    assert sers.read("motion.kind") == "jog"
    sers.advance(2.0)
    assert sers.read("motion.kind") == "jog"  # no 500 ms timeout for a jog from a program
    assert host.ask("#S\r").startswith(b"#S\r\nok")
    sers.settle()
    assert sers.read("motion.kind") is None


# ======================================================================================
# trace mode (§4.5.4, G-TRACE)
# ======================================================================================
@pytest.mark.manual("§4.5.4", "trace mode: TRON, then each TR executes one program step")
def test_trace_mode_single_steps(sers: Plant) -> None:
    host = sers.host
    download(host, "O1=1", "O2=1", "O3=1", "PE")
    assert host.ask("#TR?\r") == b"#TR?\rTR=0\n\r\nok1\n\r"
    assert host.ask("#TRON\r") == b"#TRON\r\nok1\n\r"
    assert host.ask("#TR?\r") == b"#TR?\rTR=1\n\r\nok1\n\r"
    run(host)
    sers.advance(0.1)
    assert out(sers, 1) is False  # nothing runs by itself
    assert host.ask("#TR\r") == b"#TR\r1: O1=1\n\r\nok1\n\r"
    sers.advance(0.1)
    assert (out(sers, 1), out(sers, 2)) == (True, False)
    assert host.ask("#TR\r") == b"#TR\r2: O2=1\n\r\nok1\n\r"
    sers.advance(0.1)
    assert (out(sers, 2), out(sers, 3)) == (True, False)
    assert running(sers)
    assert host.ask("#TROFF\r") == b"#TROFF\r\nok1\n\r"
    assert host.ask("#TR?\r") == b"#TR?\rTR=0\n\r\nok1\n\r"
    finish(sers, 0.1)
    assert out(sers, 3) is True


def test_tr_starts_at_the_listed_line(sers: Plant) -> None:
    host = sers.host
    download(host, "O1=1", "O2=1", "O3=1", "PE")
    host.ask("#LIST 2\r")
    assert host.ask("#TR\r") == b"#TR\r2: O2=1\n\r\nok1\n\r"
    assert host.ask("#TR?\r") == b"#TR?\rTR=1\n\r\nok1\n\r"
    assert (out(sers, 1), out(sers, 2)) == (False, True)


def test_list_arguments_beyond_the_grammar_end_the_statement(sers: Plant) -> None:
    """LIST takes '.', '-', '+', n, -n or n.m and LISTP n or n.m (§4.2): what follows a complete
    argument is the next statement, here an error, as after ``V=1.2.3``.  (Found by fuzzing:
    ``LIST 1.2.3``, ``LIST---`` and ``LISTP 1.2.3`` stopped the drive answering.)"""
    host = sers.host
    download(host, "O1=1", "O2=1", "O3=1", "PE")
    assert host.ask("#LIST 1.2.3\r") == (b"#LIST 1.2.3\r1: O1=1\n\r2: O2=1\n\r3: O3=1\n\r4: PE\n\r"
                                         b"\n*Anweisung erwartet\n\r")  # (LIST 1.2 ran at the '.': position 1)
    assert host.ask("#LIST +5\r") == b"#LIST +5\r2: O2=1\n\r\n*Anweisung erwartet\n\r"
    assert host.ask("#LIST-------\r") == b"#LIST--1: O1=1\n\r-\n*Datum oder Parameter erwartet\n\r----\r"
    answer = host.ask("#LISTP 1.2.3\r")
    assert answer.startswith(b"#LISTP 1.2.3\rP1=0\n\r") and answer.endswith(b"P123=1mm\n\r\n*Anweisung erwartet\n\r")
    assert answer.count(b"\n\rP") == 20 - 1  # 2 x 10 parameters from index 1
    assert host.ask("#LISTP 3\r").startswith(b"#LISTP 3\rP3=0\n\r\nok")
    assert host.ask("#P11?\r").startswith(b"#P11?\rP11=0\n\r\nok")


# ======================================================================================
# editing in programming mode (§4.2, §4.5.3, §4.9)
# ======================================================================================
@pytest.mark.manual("§4.2", "PGM: programming mode editing the program; lines are inserted at the current program position")
def test_pgm_inserts_after_the_listed_line(sers: Plant) -> None:
    host = sers.host
    download(host, "O1=1", "O2=1", "O3=1")
    assert host.ask("#PGM\r") == b"#PGM\r\npgm\n\r"
    assert host.ask("#LIST 1\r") == b"#LIST 1\r1: O1=1\n\r\npgm\n\r"
    assert host.ask("#O4=1\r") == b"#O4=1\r\npgm\n\r"
    host.ask("#QUIT\r")
    assert listing(host) == ["O1=1", "O4=1", "O2=1", "O3=1"]


@pytest.mark.manual("§4.2", "LIST0 allows inserting a line at the start of the program in programming mode")
def test_list0_inserts_at_the_start(sers: Plant) -> None:
    host = sers.host
    download(host, "O1=1", "O2=1")
    host.ask("#PGM\r")
    host.ask("#LIST0\r")
    host.ask("#ON V=50\r")
    host.ask("#QUIT\r")
    assert listing(host) == ["ON", "V=50", "O1=1", "O2=1"]


def test_pgm_without_list_appends_after_download(sers: Plant) -> None:
    host = sers.host
    download(host, "O1=1", "O2=1")
    host.ask("#PGM\r")
    host.ask("#O3=1\r")
    host.ask("#QUIT\r")
    assert listing(host) == ["O1=1", "O2=1", "O3=1"]


@pytest.mark.manual("§4.2", "DEL deletes the current line in programming mode")
def test_del_deletes_the_current_line(sers: Plant) -> None:
    host = sers.host
    download(host, "O1=1", "O2=1", "O3=1")
    host.ask("#PGM\r")
    host.ask("#LIST 2\r")
    assert host.ask("#DEL\r") == b"#DEL\r\npgm\n\r"
    host.ask("#QUIT\r")
    assert listing(host) == ["O1=1", "O3=1"]
    refused(host, "#DEL\r", 22)  # outside programming mode


@pytest.mark.manual("§4.2", "C n changes the value of the assignment at the current program position")
def test_c_changes_a_constant(sers: Plant) -> None:
    host = sers.host
    download(host, "ON", "V=100", "W=360 E")
    host.ask("#PGM\r")
    host.ask("#LIST 2\r")
    assert host.ask("#C 500\r") == b"#C 500\r\npgm\n\r"
    host.ask("#LIST 3\r")
    host.ask("#C 90\r")
    host.ask("#QUIT\r")
    assert listing(host) == ["ON", "V=500", "W=90", "E"]
    run(host)
    finish(sers, 10)
    assert query(host, "V") == "500U/min"
    assert degrees(sers) == pytest.approx(90, abs=1e-3)


@pytest.mark.parametrize("line", [1, 3])
def test_c_on_a_non_constant_is_errno_49(sers: Plant, line: int) -> None:
    host = sers.host
    download(host, "ON", "X=5", "V=X")
    host.ask("#PGM\r")
    host.ask(f"#LIST {line}\r")
    refused(host, "#C 5\r", 49)
    host.ask("#QUIT\r")
    assert listing(host) == ["ON", "X=5", "V=X"]


@pytest.mark.manual("§4.6.2", "each label number may be defined only once in the program (errno 83 'label bereits definiert: L')")
def test_duplicate_label_is_errno_83(sers: Plant) -> None:
    host = sers.host
    host.ask("#NEW\r")
    host.ask("#L1 O1=1\r")
    answer = host.ask("#O2=1 L1\r").decode("latin-1")
    assert "\n*label bereits definiert: L1\n\r" in answer
    host.ask("#QUIT\r")
    assert query(host, "P1137") == "83"
    assert listing(host) == ["L1", "O1=1"]  # the whole line was refused


def test_malformed_line_is_refused_and_the_program_unchanged(sers: Plant) -> None:
    host = sers.host
    host.ask("#NEW\r")
    host.ask("#O1=1\r")
    answer = host.ask("#V=10 FOO\r").decode("latin-1")
    assert f"\n*{error_text(21)}\n\r" in answer
    assert "pgm" not in answer
    assert host.ask("#GT\r").decode("latin-1").endswith(f"\n*{error_text(25)}\n\r")
    assert host.ask("#O2=1\r") == b"#O2=1\r\npgm\n\r"  # still in programming mode
    host.ask("#QUIT\r")
    assert listing(host) == ["O1=1", "O2=1"]


@pytest.mark.manual("§4.4", "program memory 2 KByte in the standard version (errno 5 'EEPROM Speicher voll' when full)")
def test_eeprom_full_is_errno_5(sers: Plant) -> None:
    host = sers.host
    assert query(host, "P1122") == "1024"  # 2 KB standard
    ten = " ".join(["O1=1"] * 10)  # 10 × 6 bytes (G-MEM)
    host.ask("#NEW\r")
    for _ in range(34):
        assert host.ask(f"#{ten}\r").endswith(b"\npgm\n\r")
    assert host.ask("#O1=1\r").endswith(b"\npgm\n\r")  # 341 × 6 = 2046 bytes
    refused(host, "#O1=1\r", 5)
    assert host.ask("#E\r").endswith(b"\npgm\n\r")  # 2 bytes still fit
    refused(host, "#E\r", 5)
    host.ask("#QUIT\r")
    assert query(host, "P1122") == "0"
    rows = listing(host)
    assert len(rows) == 342
    assert rows[-1] == "E"


@pytest.mark.manual("§4.5.2", "the sequence program is written into the EEPROM of the SERS (kept without supply)")
def test_program_survives_a_power_cycle_and_runs_again(plant_factory, tmp_path) -> None:
    plant = plant_factory({}, state_dir=tmp_path)
    host = plant.host
    download(host, "ON", "W=90 E", "O1=1", "PE")
    run(host)
    finish(plant, 10)
    assert degrees(plant) == pytest.approx(90, abs=1e-3)
    power_cycle(plant)
    assert out(plant, 1) is False
    assert listing(host) == ["ON", "W=90", "E", "O1=1", "PE"]
    start = degrees(plant)
    run(host)
    finish(plant, 10)
    assert degrees(plant) - start == pytest.approx(90, abs=1e-3)
    assert out(plant, 1) is True
