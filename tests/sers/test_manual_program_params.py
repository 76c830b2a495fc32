"""Manual §4.8.5 (time delays, counters, markers, list option, master parameters) and the small
sections of §4.8.6 (address, language, arithmetic registers) through the pty on virtual time."""

from __future__ import annotations

import pytest

from tests.sers.conftest import Plant
from tests.sers.test_programs import download, finish, out, query, refused, run


def _time_until(plant: Plant, predicate, timeout: float = 10.0) -> float:  # type: ignore[no-untyped-def]
    dev = plant.runtime.device(plant.name)
    assert plant.runtime.run_until(lambda: predicate(dev), timeout)
    return plant.runtime.now()


@pytest.mark.manual("§4.8.5.1", "the smallest programmable delay is 10 ms (D=0.1); D=0.5 waits 50 ms "
                    "(P1141=1: factor 1.0)")
def test_fractional_delay(plant_factory) -> None:
    plant = plant_factory({"params": {"P1141": 1}})
    download(plant.host, "O1=1", "D=0.5", "O2=1", "PE")
    run(plant.host)
    t1 = _time_until(plant, lambda d: d.read("output.O1"))
    t2 = _time_until(plant, lambda d: d.read("output.O2"))
    assert t2 - t1 == pytest.approx(0.05, abs=0.002)


@pytest.mark.manual("§4.8.5.1", "P1141=0 (default): the delay D of versions V01..V03 with factor 1.2 "
                    "(D=10 gives 1.2 seconds)")
def test_default_delay_factor(sers: Plant) -> None:
    download(sers.host, "O1=1", "D=10", "O2=1", "PE")
    run(sers.host)
    t1 = _time_until(sers, lambda d: d.read("output.O1"))
    t2 = _time_until(sers, lambda d: d.read("output.O2"))
    assert t2 - t1 == pytest.approx(1.2, abs=0.002)


@pytest.mark.manual("§4.8.5.1", "D2 range 0.0 to 6553.5")
def test_d2_range(sers: Plant) -> None:
    host = sers.host
    assert host.ask("#D2=6553.5\r").endswith(b"ok1\n\r")
    refused(host, "#D2=6553.6\r", 1)


@pytest.mark.manual("§4.8.5.1", "the waiting time can be reloaded (extended) with D2=value as long as the jump "
                    "has not been executed")
def test_d2_can_be_extended(sers: Plant) -> None:
    download(sers.host, "D2=5 GT60", "D=2", "D2=10", "WAIT I1=1", "PE", "L60", "O2=1", "PE")
    run(sers.host)
    t0 = sers.runtime.now()
    t_jump = _time_until(sers, lambda d: d.read("output.O2"))
    # reloaded 0.24 s after the start (D=2 × 1.2): the jump comes 1.0 s after the reload
    assert t_jump - t0 == pytest.approx(0.24 + 1.0, abs=0.005)


@pytest.mark.manual("§4.8.5.1", "DB can be tested with 'IF DB' or 'IF DB=1'")
def test_if_db(sers: Plant) -> None:
    download(sers.host, "D2=1", "L1", "IF DB GT 2", "GT 1", "L2", "O1=1", "PE")
    run(sers.host)
    finish(sers)
    assert out(sers, 1)


@pytest.mark.manual("§4.8.5.2", "C1 and C2 are unsigned 16-bit counters, C3 an unsigned 32-bit counter")
def test_counter_ranges(sers: Plant) -> None:
    host = sers.host
    assert host.ask("#C1=65535 C2=0 C3=4294967295\r").endswith(b"ok1\n\r")
    refused(host, "#C1=-1\r", 2)
    refused(host, "#C3=4294967296\r", 1)


@pytest.mark.manual("§4.8.5.2", "with P1014=3 (relative positioning with overflow counter) C1 is signed "
                    "(-32768 bis 32768): a host writes a negative overflow count back")
def test_c1_is_signed_in_overflow_mode(sers: Plant) -> None:
    host = sers.host
    assert host.ask("#P1014=3 C1=-32768\r").endswith(b"ok1\n\r")
    assert query(host, "C1") == "-32768"
    assert host.ask("#C1=32767\r").endswith(b"ok1\n\r")
    refused(host, "#C1=32768\r", 1)  # 16 bits with a sign: the manual's 32768 is 32767 [SIM-CHOICE]
    refused(host, "#C1=-32769\r", 2)
    assert query(host, "C1") == "32767"
    assert host.ask("#P1014=0 C1=0\r").endswith(b"ok3\n\r")  # (the warning of the refusals above)
    refused(host, "#C1=-1\r", 2)  # unsigned again outside mode 3


@pytest.mark.manual("§4.8.5.3", "markers M1..M3 can be set and cleared in a program and used in IF "
                    "(the block repeats while M1 is set)")
def test_marker_loop(sers: Plant) -> None:
    download(sers.host, "M1=1 R0=0", "L1", "X=R0 +1 R0=X", "IF R0=3 M1=0", "IF M1=1 GT 1", "PE")
    run(sers.host)
    finish(sers)
    assert float(query(sers.host, "R0")) == 3


@pytest.mark.manual("§4.8.5.4", "P1028 bit 0: the statement number is listed; without it no number")
def test_list_option_numbers(sers: Plant) -> None:
    host = sers.host
    download(host, "O1=1", "O2=1")
    host.ask("#P1028=0\r")
    assert host.ask("#LIST\r") == b"#LIST\rO1=1\n\rO2=1\n\r\nok1\n\r"
    host.ask("#P1028=1\r")
    assert host.ask("#LIST\r") == b"#LIST\r1: O1=1\n\r2: O2=1\n\r\nok1\n\r"


@pytest.mark.manual("§4.8.5.4", "P1028 bit 3: line breaks are listed as the user programmed them (else one "
                    "statement per line)")
def test_list_option_user_line_breaks(sers: Plant) -> None:
    host = sers.host
    download(host, "O1=1 O2=1", "O3=1")
    host.ask("#P1028=8\r")
    assert host.ask("#LIST\r") == b"#LIST\rO1=1 O2=1\n\rO3=1\n\r\nok1\n\r"


@pytest.mark.manual("§4.2", "';' Strichkomma verhindert einen Zeilenumbruch bei Programmeingabe in der aktuellen "
                    "Zeile")
def test_a_semicolon_at_the_end_of_a_line_continues_it_with_the_next(sers: Plant) -> None:
    host = sers.host
    download(host, "O1=1;", "O2=1 ;", "O3=1", "O4=1; O5=1")  # a ';' between statements is a separator
    host.ask("#P1028=9\r")
    assert host.ask("#LIST\r") == b"#LIST\r1: O1=1 O2=1 O3=1\n\r4: O4=1 O5=1\n\r\nok1\n\r"
    host.ask("#P1028=1\r")  # without bit 3 every statement has its row, as before
    assert host.ask("#LIST\r") == b"#LIST\r1: O1=1\n\r2: O2=1\n\r3: O3=1\n\r4: O4=1\n\r5: O5=1\n\r\nok1\n\r"


@pytest.mark.manual("§4.8.5.5", "P1110 is always 1 after switching on; it is not stored in the EEPROM")
def test_p1110_after_power_on(plant_factory, tmp_path) -> None:
    plant = plant_factory({}, state_dir=tmp_path)
    host = plant.host
    host.ask("#P1110=0 PSAVE\r")
    assert query(host, "P1110") == "0"
    plant.runtime.power_cycle(plant.name)
    plant.advance(2.0)
    assert query(host, "P1110") == "1"


@pytest.mark.manual("§4.8.6.5", "P1050: the SERS enters the drive address set on DIP switch 2")
@pytest.mark.manual("§3.1.1", "the drive number is set binary on DIP switch 2 bits 1..7 (1..127 for slaves), "
                    "e.g. 67")
def test_own_address(plant_factory) -> None:
    plant = plant_factory({"address": 67})
    assert plant.host.ask("#67P1050?\r") == b"#67P1050?\rP1050=67\n\r\nok1\n\r"


@pytest.mark.manual("§3.1.1", "address 0 configures a master; addressed as 200 it behaves like a slave and "
                    "can be programmed")
@pytest.mark.manual("§3.6.2", "a master (address 0) addressed with '200' behaves like a slave")
def test_master_answers_as_200(plant_factory) -> None:
    plant = plant_factory({"address": 0})
    assert plant.host.ask("#200P1050?\r") == b"#200P1050?\rP1050=0\n\r\nok1\n\r"


@pytest.mark.manual("§4.8.6.11", "P265: 0 German, 1 English (the messages)")
def test_language(sers: Plant) -> None:
    host = sers.host
    assert host.ask("#P9999?\r").endswith("*Parameter nicht vorhanden\n\r".encode("latin-1"))
    host.ask("#P265=1\r")
    answer = host.ask("#P9999?\r")
    assert b"*" in answer and b"Parameter nicht vorhanden" not in answer


@pytest.mark.manual("§4.8.6.13", "R0..R5 (P1080..P1085) are free signed 32-bit variables")
def test_registers(sers: Plant) -> None:
    host = sers.host
    for n in range(6):
        assert host.ask(f"#R{n}=-{n + 1}\r").endswith(b"ok1\n\r")
        assert float(query(host, f"P{1080 + n}")) == -(n + 1)


@pytest.mark.manual("§4.8.6.14", "P1092=1: with a signal at the external service switch input the jog "
                    "functions on I1..I8 are enabled")
def test_external_service_switch(plant_factory) -> None:
    plant = plant_factory({"params": {"P1092": 1}})
    plant.set("input.I2", True)
    plant.advance(0.2)
    assert plant.read("motion.kind") is None  # P1021 = 0: no jog function
    plant.set("input.I2", False)
    plant.set("input.service_ext", True)
    plant.set("input.I2", True)
    plant.advance(0.2)
    assert plant.read("motion.kind") == "jog"
