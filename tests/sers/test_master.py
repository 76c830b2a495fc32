"""Master mode (manual §3.6.2, §4.6.12 "Master Betrieb", spec §3.8, T-17): a master at DIP
address 0 runs its program and drives slaves 1 and 2 on the same RS-485 line."""

from __future__ import annotations

import pytest

from devsim.core.clock import VirtualClock
from devsim.core.nvram import NonVolatileMemory
from devsim.devices.sers.device import SersDevice
from tests.sers.conftest import Plant

MASTER = [
    "ON", "L1", "X=1000", "Z=1", "ON", "V=X", "W=500", "WAIT I3=1", "E", "WAIT POS=1", "Z=0",
    "V=2000", "W=1000 E", "Z=2", "RUN 2", "WAIT P0=0", "Z=0", "V=10", "W=20 E", "GT1",
]
SLAVE2 = ["L1", "PE", "L2", "ON V=600", "W=90 E", "O1=1", "RT"]


def download(plant: Plant, address: int, lines: list[str]) -> None:
    host = plant.host
    assert host.ask(f"#{address} NEW\r").endswith(b"\npgm\n\r")
    for line in lines:
        assert host.ask(f"#{line}\r").endswith(b"\npgm\n\r"), line
    assert host.ask("#QUIT\r").endswith(b"ok1\n\r")


@pytest.fixture
def line(plant_factory) -> Plant:
    plant: Plant = plant_factory({"address": 0}, {"address": 1}, {"address": 2})
    download(plant, 200, MASTER)  # #200 addresses the master like a slave (§3.1.1)
    download(plant, 2, SLAVE2)
    return plant


def sent_by_master(plant: Plant) -> list[bytes]:
    return list(plant.runtime.device("sers0").model.master.sent)


@pytest.mark.manual("§4.6.12", "the master example: a master at address 0 commands slaves 1 and 2 (Z=1 ... Z=0, RUN 2 in slave 2)")
@pytest.mark.manual("§4.5.2", "a master program sends the statements after Z=address to that slave; Z=0 addresses the master itself")
@pytest.mark.manual("§3.6.2", "address 0 makes a SERS a master that commands other SERS units")
def test_t17_master_drives_two_slaves(line: Plant) -> None:
    host = line.host
    assert host.ask("#200 RUN\r").endswith(b"ok1\n\r")
    line.advance(0.1)
    # the master has switched slave 1 on, given it V = X = 1000 and W, and now polls I3
    sent = sent_by_master(line)
    assert sent[:3] == [b"#1ON\r", b"#1V=1000\r", b"#1W=500\r"]
    assert sent[3:] and set(sent[3:]) == {b"#1P2=1300\r"}
    assert line.read("energized", "sers1") is True
    assert line.read("param.V", "sers1") == 1000
    assert line.read("motion.kind", "sers1") is None  # waits for I3 of drive 1
    line.set("input.I3", True, "sers1")
    line.advance(0.05)
    assert line.read("motion.kind", "sers1") == "position"
    # slave 1 positions 500°, then the master itself moves 1000°, then slave 2 runs L2
    dev2 = line.runtime.device("sers2")
    assert line.runtime.run_until(lambda: dev2.read("output.O1") is True, 20)
    assert line.read("param.P51", "sers1") == pytest.approx(500, abs=0.02)
    assert line.read("param.P51", "sers0") == pytest.approx(1000, abs=0.02)
    assert line.read("param.P51", "sers2") == pytest.approx(90, abs=0.02)
    sent = sent_by_master(line)
    assert b"#1E\r" in sent and b"#2RUN 2\r" in sent
    assert b"#1P2=336\r" in sent and b"#2P2=0\r" in sent
    # after slave 2's program ended the master moves 20° and starts over at L1
    assert line.runtime.run_until(lambda: sent_by_master(line).count(b"#1ON\r") == 2, 20)
    assert line.read("param.P51", "sers0") == pytest.approx(1020, abs=0.02)


@pytest.mark.manual("§3.6.2", "a master queries inputs and status of other SERS drives")
def test_master_reads_a_slave_value_into_x(plant_factory) -> None:
    plant: Plant = plant_factory({"address": 0}, {"address": 1, "params": {"V": 750}})
    download(plant, 200, ["Z=1", "X=V", "Z=0", "R0=X"])
    plant.host.ask("#200 RUN\r")
    plant.advance(0.05)
    assert b"#1P3=91\r" in sent_by_master(plant)
    assert plant.read("param.R0", "sers0") == 750


def test_a_master_asking_for_a_broadcast_target_gets_a_star(sers: Plant) -> None:
    """P1 may hold ``*`` (Z=*, §4.8.5.5): asked through P3 or P2 the drive answers ``*`` as its
    query does (found by fuzzing: the answer died on the star)."""
    host = sers.host
    assert host.ask("#Z=*\r") == b"#Z=*\r\nok1\n\r"
    assert host.ask("#P1?\r") == b"#P1?\rP1=*\n\r\nok1\n\r"
    assert host.ask("#P3=1\r") == b"#P3=1\rP3=*\n\r\nok1\n\r"
    assert host.ask("#P2=1\r") == b"#P2=1\rP2=*\n\r\nok1\n\r"


def test_a_broadcast_target_is_no_number(sers: Plant) -> None:
    """With Z=* (P1 holds '*') every use of Z as a number is error 19, as V=Z already was: X=Z,
    a comparison, arithmetic, a master's P2=Z.  (Found by fuzzing: they raised TypeError and the
    drive went silent.)  Z=0 ends it."""
    host = sers.host
    host.ask("#Z=*\r")
    for statement in ("X=Z", "X=5-Z", "-Z", "P2=Z"):
        assert host.ask(f"#{statement}\r") == f"#{statement}\n** nur bei P1 oder z erlaubt\n\r\r".encode()
    assert host.ask("#IF Z=1 O1=1\r") == b"#IF Z=1 O1=1\r\n** nur bei P1 oder z erlaubt\n\r"
    assert host.ask("#Z?\r").startswith(b"#Z?\rZ=*\n\r")
    host.ask("#Z=0\r")
    assert host.ask("#X=Z\r").startswith(b"#X=Z\r\nok")


def test_master_broadcast_does_not_wait(plant_factory) -> None:
    plant: Plant = plant_factory({"address": 0}, {"address": 1}, {"address": 2})
    download(plant, 200, ["Z=*", "ON", "Z=0", "O1=1"])
    plant.host.ask("#200 RUN\r")
    plant.advance(0.01)
    assert sent_by_master(plant) == [b"#*ON\r"]
    assert plant.read("energized", "sers1") and plant.read("energized", "sers2")
    assert plant.read("output.O1", "sers0") is True


def test_missing_slave_is_a_program_error(plant_factory) -> None:
    plant: Plant = plant_factory({"address": 0}, {"address": 1})
    download(plant, 200, ["Z=5", "ON"])
    plant.host.ask("#200 RUN\r")
    plant.advance(0.2)  # no answer within 100 ms
    assert plant.read("param.P0", "sers0") == 0
    assert plant.read("P12", "sers0") & 128


def test_host_sees_the_master_traffic_on_the_line(line: Plant) -> None:
    assert line.host.ask("#200 RUN\r") == b"#200 RUN\r\nok1\n\r"
    line.advance(0.01)
    data = line.host.read_exact(len(b"#1ON\r#1ON\r\nok1\n\r"))
    # what the master sends, then slave 1's echo and acknowledgement: all on the one line
    assert data == b"#1ON\r#1ON\r\nok1\n\r"


@pytest.mark.manual("§4.8.3.1", "errno 19: * nur bei P1 oder z erlaubt")
@pytest.mark.parametrize("statement", ["X=*", "P1047=*"])
def test_the_accumulator_takes_no_star(sers: Plant, statement: str) -> None:
    """``*`` is a value only for P1/Z; the accumulator X (P1047) refuses it like V or W do,
    and keeps its value (it was set to 0)."""
    host = sers.host
    host.ask("#X=5\r")
    assert host.ask(f"#{statement}\r") == f"#{statement}\n** nur bei P1 oder z erlaubt\n\r\r".encode("latin-1")
    assert sers.read("param.P1137") == 19
    assert sers.read("param.P1047") == 5


@pytest.mark.manual("§4.5.2", "after Z=address every statement is sent to that axis; only Z=0 gives them to the master itself")
@pytest.mark.manual("§4.2", "Achsnummer '*' addresses all axes: each drive carries out a broadcast line once")
def test_a_slaves_echo_is_no_statement_for_the_master(plant_factory) -> None:
    """With ``broadcast_reply: lowest_address`` slave 1 echoes what it answers: the master's own
    ``Z=* V=55`` (``#*V=55``) and the host's ``#*+1``.  The master hears the echo on the line but
    takes only its slave's answer from it: its own V stays, and the host's broadcast adds 1 to
    every accumulator once (the master's went up by 2)."""
    config = {"broadcast_reply": "lowest_address"}
    plant = plant_factory({"address": 0, **config}, {"address": 1, **config}, {"address": 2, **config})
    host = plant.host
    download(plant, 200, ["Z=*", "V=55", "Z=0"])
    assert host.ask("#200 RUN\r") == b"#200 RUN\r\nok1\n\r"
    plant.advance(0.1)
    host.expect(b"#*V=55\r#*V=55\r\nok1\n\r")  # the master's line, slave 1's echo and answer
    assert [plant.read("param.V", f"sers{n}") for n in (0, 1, 2)] == [100, 55, 55]
    assert host.ask("#*X=0\r") == b"#*X=0\r\nok1\n\r"
    assert host.ask("#*+1\r") == b"#*+1\r\nok1\n\r"
    assert [plant.read("param.P1047", f"sers{n}") for n in (0, 1, 2)] == [1, 1, 1]


@pytest.mark.manual("§4.1", "after an address every following command is for the drive it names, the others ignore them")
def test_the_master_takes_no_part_of_a_slaves_answer_for_a_line_of_its_own(plant_factory) -> None:
    """A slave in RS-485 mode answers the master without an echo, ``\\nok1\\n\\r``: the master
    heard that LF right after its own line and sent it on as the echo of a host's CR LF pair."""
    plant = plant_factory({"address": 0}, {"address": 1, "params": {"P1017": 2}})
    host = plant.host
    download(plant, 200, ["Z=1", "V=11", "V=12", "Z=0"])
    assert host.ask("#200 RUN\r") == b"#200 RUN\r\nok1\n\r"
    plant.advance(0.1)
    host.expect(b"#1V=11\r\nok1\n\r#1V=12\r\nok1\n\r")
    assert host.ask("#V?\r") == b"V=12U/min\n\r\nok1\n\r"  # drive 1 (no echo) answers: the master sent #1
    assert plant.read("param.V", "sers1") == 12


def _lone_master(program: list[str]) -> tuple[SersDevice, VirtualClock, bytearray]:
    """A master at address 0 on a line with no slave: the host may answer in a slave's place."""
    clock = VirtualClock()
    master = SersDevice(clock=clock, config={"address": 0, "boot_time": 0}, nvram=NonVolatileMemory(None))
    out = bytearray()
    master.main.attach(out.extend)
    clock.advance(0.1)
    for line in ["#200 NEW", *(f"#{s}" for s in program), "#QUIT", "#200 RUN"]:
        master.main.feed(f"{line}\r".encode())
        clock.advance(0.01)
    assert master.model.master.awaiting
    return master, clock, out


@pytest.mark.manual("§3.6.2", "a master queries inputs and status of other SERS drives")
@pytest.mark.parametrize("value", [b"1.2.3", b".", b"-.", b"9" * 400])
@pytest.mark.parametrize(("program", "asked"), [(["Z=1", "X=V", "Z=0", "R0=X"], b"P3"),
                                                (["Z=1", "WAIT I3=1", "Z=0", "O1=1"], b"P2")])
def test_a_slave_answer_that_is_no_number_is_no_value(program: list[str], asked: bytes, value: bytes) -> None:
    """What comes back in a slave's P3/P2 answer must be a number (G-MASTER): ``1.2.3`` or 400
    digits from the line is no value, as no answer line is (X=V: X=0; WAIT/IF: the program
    error of a failed request).  (Found by fuzzing: float() raised out of the port's feed.)"""
    master, clock, out = _lone_master(program)
    master.main.feed(b"\n" + asked + b"=" + value + b"\n\r\nok1\n\r")
    clock.advance(0.2)
    assert not master.model.master.awaiting
    if asked == b"P3":
        assert master.read("param.R0") == 0
    else:
        assert master.read("param.P0") == 0 and master.read("P12") & 128
    out.clear()
    master.main.feed(b"#200 VER\r")
    assert b"P1133=120901" in bytes(out)


@pytest.mark.manual("§4.8.5.5", "P1110=0: the master does not wait for the end of its own positioning, so it can "
                    "command other axes meanwhile; P1110=1: it waits before the next line")
@pytest.mark.parametrize(("p1110", "at_once"), [(0, True), (1, False)])
def test_p1110_master_waits_for_its_positioning(plant_factory, p1110: int, at_once: bool) -> None:
    plant: Plant = plant_factory({"address": 0})
    download(plant, 200, ["ON", "W=3600", "E", "O1=1", "PE"])
    assert plant.host.ask(f"#200 P1110={p1110} RUN\r").endswith(b"ok1\n\r")
    plant.advance(0.05)
    assert plant.read("motion.kind") == "position"
    assert plant.read("output.O1") is at_once
    plant.settle()
    plant.advance(0.01)
    assert plant.read("output.O1") is True
