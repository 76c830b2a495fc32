"""The manual's three example programs (spec pcd4h3.md §6.3–§6.5, §5.2's kinematics) played by a
host over S-Bus on a real pty, as the GRAFTEC steps would: chip traces and timings."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.pcd4h3.helpers import Station, flag, load, reg, run

EXAMPLES_23 = {"cyclic_reads": ["FRdAP", "FRdSV"], "display": {1: {"reg1": "RActP", "reg2": "RSetV"}}}


def motion(pcd: Station) -> list[str]:
    """The chip traffic since the last look, without the cyclic reads."""
    trace = [t for t in pcd.sim.read("axis.1.trace") if t not in ("C:0A R:4", "C:07 R:4")]
    pcd.sim.set("axis.1.trace", [])
    return trace


def wait_flag(pcd: Station, symbol: str, timeout: float, start: float | None = None) -> float:
    """Virtual time from ``start`` (default: now) until the flag reads 1, the step's flags having
    been processed first (a GRAFTEC transition is looked at after the next AxHndlg)."""
    if start is None:
        start = pcd.sim.now()
    assert pcd.sim.run_until(lambda d: d.read(f"axis.1.{symbol}"), timeout), symbol
    assert pcd.read_flags(flag(symbol)) == [1]
    return pcd.sim.now() - start


@pytest.mark.manual("§9.2", "Beispiel 2: Breakposition 70 mm, dort Geschwindigkeit 0,02 m/s bis 100 mm; "
                    "zurück langsam bis 70 mm, schnell bis 0")
@pytest.mark.manual("§9.2", "nach dem Laden der Breakposition muss das Statusflag BrkPos mit FResSF zuerst "
                    "zurückgesetzt werden")
def test_example_2_break_position_both_ways(make: Callable[..., Station]) -> None:
    pcd = make(EXAMPLES_23)
    pcd.write_flags(flag("DplM"), 1)
    pcd.sim.set("axis.1.trace", [])
    load(pcd, DestP=1000, BrkP=700, StaFRR=0)  # ST 1 "forward"
    run(pcd, "FLdDA", "FLdBPA", "FResSF", "FStart", cycles=0)
    assert motion(pcd) == ["C:1F D:00 02 D:00 01 D:86 A0", "C:1D D:00 00", "C:20 D:00 01 D:11 70", "C:01"]
    assert wait_flag(pcd, "BrkPos", 10) == pytest.approx(3.88, abs=0.08)
    assert pcd.read_registers(reg("RSetV"))[0] == pytest.approx(244, abs=8)  # already braking
    load(pcd, Veloc=200)  # ST 2 "modify velocity"
    run(pcd, "FLdVA", "FStart", cycles=0)
    assert wait_flag(pcd, "OnDest", 10) == pytest.approx(6.34 - 3.88, abs=0.1)
    assert motion(pcd) == ["C:1F D:00 08 D:00 06 D:D1 EC", "C:01"]
    pcd.sim.advance(3.0)  # ST 3 "ld timer"
    load(pcd, DestP=0)  # ST 4 "backwards"
    run(pcd, "FLdDA", "FResSF", "FStart", cycles=0)
    assert wait_flag(pcd, "BrkPos", 10) == pytest.approx(2.51, abs=0.08)
    assert motion(pcd) == ["C:1F D:00 02 D:00 00 D:00 00", "C:1D D:00 00", "C:01"]
    assert pcd.sim.read("axis.1.display")[1] == "-  200"  # the set velocity, 1/10 mm/s, signed (G-11)
    load(pcd, Veloc=500)  # ST 5 "modify velocity"
    run(pcd, "FLdVA", "FStart", cycles=0)
    assert wait_flag(pcd, "OnDest", 10) == pytest.approx(6.51 - 2.51, abs=0.12)
    assert motion(pcd) == ["C:1F D:00 08 D:00 11 D:0C CD", "C:01"]
    pcd.sim.advance(0.5)
    assert abs(pcd.read_registers(reg("RActP"))[0]) <= 1
    assert pcd.sim.read("axis.1.display") == ["     0", "     0"]


@pytest.mark.manual("§9.3", "Automatikbetrieb: 0 → 150 mm mit Breakpositionen 30 und 110 mm, dann fünfmal "
                    "relativ −30 mm")
def test_example_3_automatic_cycle(make: Callable[..., Station]) -> None:
    pcd = make(EXAMPLES_23)
    pcd.sim.set("axis.1.trace", [])
    load(pcd, Veloc=100, DestP=1500, BrkP=300, StaFRR=0)  # ST 10 "def. motion 1"
    run(pcd, "FLdVA", "FLdDA", "FLdBPA", "FResSF", "FStart", cycles=0)
    assert wait_flag(pcd, "BrkPos", 10) == pytest.approx(3.50, abs=0.08)
    assert motion(pcd) == ["C:1F D:00 02 D:00 02 D:49 F0", "C:1F D:00 08 D:00 03 D:68 F6", "C:1D D:00 00",
                           "C:20 D:00 00 D:75 30", "C:01"]
    load(pcd, Veloc=500, BrkP=1100)  # ST 11
    run(pcd, "FLdVA", "FLdBPA", "FResSF", "FStart", cycles=0)
    assert 3.50 + wait_flag(pcd, "BrkPos", 10) == pytest.approx(6.75, abs=0.1)
    assert motion(pcd) == ["C:1F D:00 08 D:00 11 D:0C CD", "C:1D D:00 00", "C:20 D:00 01 D:AD B0", "C:01"]
    load(pcd, Veloc=100)  # ST 12
    run(pcd, "FLdVA", "FStart", cycles=0)
    assert 6.75 + wait_flag(pcd, "OnDest", 10) == pytest.approx(9.59, abs=0.15)
    assert motion(pcd) == ["C:1F D:00 08 D:00 03 D:68 F6", "C:01"]
    pcd.sim.advance(2.0)  # ST 13
    load(pcd, Veloc=300)  # ST 15: loaded, no start
    run(pcd, "FLdVA", cycles=1)
    assert motion(pcd) == ["C:1F D:00 08 D:00 0A D:3A E1"]
    for end in (1200, 900, 600, 300, 0):  # ST 16/17 five times
        load(pcd, DestP=-300)
        run(pcd, "FLdDR", "FStart", cycles=0)
        assert wait_flag(pcd, "OnDest", 10) == pytest.approx(3.47, abs=0.08)
        assert motion(pcd) == ["C:1F D:00 03 D:FF FF D:8A D0", "C:01"]
        pcd.sim.advance(1.0)
        assert pcd.read_registers(reg("RActP"))[0] == pytest.approx(end, abs=1)
    assert pcd.sim.read("axis.1.comers") == 0


@pytest.mark.manual("§9.3", "Manuellbetrieb: solange die Taste gedrückt ist ±0,02 m/s; losgelassen: Stop mit "
                    "der definierten Stopart; per Taste die Istposition als Nullposition")
@pytest.mark.manual("§7.4 FForw", "realisiert, indem die grösstmögliche positive Zielposition geladen und ein Startbefehl "
                    "erteilt wird")
def test_example_3_manual_jog_and_zero(make: Callable[..., Station]) -> None:
    """ST 7/8: jog forward at 20 mm/s, smooth stop on release (≈ 20 mm overrun in ≈ 2 s); ST 4:
    FSetZP makes the position 0 without motion."""
    pcd = make(EXAMPLES_23)
    pcd.sim.set("axis.1.trace", [])
    load(pcd, Veloc=200)
    run(pcd, "FLdVA", "FForw", cycles=0)
    pcd.sim.advance(3.0)
    assert motion(pcd) == ["C:1F D:00 08 D:00 06 D:D1 EC", "C:1F D:00 02 D:3F FF D:FF FF", "C:01"]
    assert pcd.read_registers(reg("RSetV"))[0] == pytest.approx(200, abs=1)
    assert pcd.sim.read("axis.1.velocity") == pytest.approx(19_980, rel=0.01)  # 19.98 mm/s physical
    released = pcd.read_registers(reg("RActP"))[0]
    run(pcd, "FStop", cycles=0)
    assert wait_flag(pcd, "OnDest", 5) == pytest.approx(2.0, abs=0.1)
    assert motion(pcd) == ["C:1F D:04 00", "C:01"]
    pcd.sim.advance(0.5)
    assert pcd.read_registers(reg("RActP"))[0] - released == pytest.approx(200, abs=8)
    mechanical = pcd.sim.read("axis.1.mechanical_position")
    run(pcd, "FSetZP", "FRdAP")
    assert motion(pcd) == ["C:02"]
    assert pcd.read_registers(reg("RActP")) == [0] and abs(pcd.sim.read("axis.1.position")) <= 1
    assert pcd.sim.read("axis.1.mechanical_position") == pytest.approx(mechanical, abs=1)
