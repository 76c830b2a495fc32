"""The PLC skips the cycles a moving axis does not need (devsim/devices/pcd4h3/lookahead.py;
issue 31, "schedule timers only for events"): with the chips computed ahead, a PCD gives the same
chips, status flags, switch signals and recorded events as the PLC that runs every cycle, at every
look of a host (random moments), through moves, breakpoints, a position error, a blocked motor,
limit and reference switches, a second axis and one that stands while the cycles read it, a user
program whose timers run out between cycles (a cycle run late reads them at its own start); and it
runs far fewer timer events.  The shared axes (the switches' axis, ``axis.N.mechanical_position``)
are the same too: each follows the motor through its position at the chip's last sample, which a
cycle's functions compute up to the cycle's length ahead of the clock (§3.3.2, §10.1)."""

from __future__ import annotations

import random
from typing import Any

import pytest

from devsim.core.clock import VirtualClock
from devsim.devices.pcd4h3 import batch, model
from devsim.devices.pcd4h3.model import Pcd4
from devsim.devices.pcd4h3.units import CHIP_SAMPLE
from tests.pcd4h3.helpers import Step, blocked, command, keys

EXAMPLE = {"h3def": {"fmah3": 48, "bar": 200, "baf": 200, "mna": 2}, "modules": 1, "variant": "H320",
           "response_delay_ms": 0}


def look(pcd: Pcd4) -> tuple[Any, ...]:
    """What a host sees now: the chips, every flag and register, the switches."""
    pcd.catch_up()
    chips = tuple((batch.snapshot(d.chip), d.chip.status) for d in pcd.drives)
    signals = tuple(pcd.signals.get(f"{name}_{n}") for n in (1, 2) for name in ("LS1", "LS2", "REF"))
    library = tuple((a.transfers, a.comers_calls, tuple(a.trace[-40:])) for a in pcd.axes)
    return (pcd.clock.now(), chips, sorted(pcd.flags.items()), sorted(pcd.registers.items()), signals, library,
            sorted(pcd.screens.items()), pcd.status, pcd.handler_calls())


def shared_axes(pcd: Pcd4) -> tuple[float, ...]:
    """Where the shared axes are now."""
    return tuple(d.axis.position() for d in pcd.drives)


def play(config: dict[str, Any], script: dict[float, list[Step]], seconds: float, seed: int) -> tuple[list[Any], list[Any], list[Any], int]:
    """The script's steps at their times and looks at random moments between them; returns the
    looks, the shared axes at the looks, the recorded events and signal changes, and the timer
    events run."""
    clock = VirtualClock()
    pcd = Pcd4(clock=clock, config={**EXAMPLE, **config})
    changes: list[Any] = []
    for n in (1, 2):
        for name in ("LS1", "LS2", "REF"):
            pcd.signals.subscribe(f"{name}_{n}", lambda signal, old, new: changes.append((clock.now(), signal, new)))
    rng = random.Random(seed)
    moments = sorted({*script, *(round(rng.uniform(0, seconds), 6) for _ in range(40))})
    looks, axes, events = [], [], 0
    for moment in [*moments, seconds]:
        events += clock.advance_to(moment)
        for step in script.get(moment, ()):
            step(pcd)
        looks.append(look(pcd))
        axes.append(shared_axes(pcd))
    pcd.close()
    return looks, axes, [*pcd.events, *changes], events


SCENARIOS: dict[str, tuple[dict[str, Any], dict[float, list[Step]], float]] = {
    "a move with a breakpoint, a second axis started later": (
        {}, {0.3: [command(1, "FLdAA", "FLdVA", "FLdDA", "FLdBPA", "FStart", Accel=400, Veloc=150, DestP=250,
                           BrkP=120)],
             0.9: [command(2, "FLdDA", "FStart", DestP=-80)]}, 4.0),
    "limit and reference switches, stopped by the limit": (
        {"emulate_user_limit_stop": True, "axes": {1: {"ls2": 20_000, "ref_switch": [8_000, 9_000]}}},
        {0.2: [command(1, "FLdAA", "FLdVA", "FForw", Accel=500, Veloc=200)]}, 3.0),
    "a blocked motor runs into the position error, reset and moved back": (
        {}, {0.2: [command(1, "FSetPE", "FLdDA", "FStart", PosEr=500, DestP=1_000), blocked(1, True)],
             1.0: [blocked(1, False), command(1, "FResSF", "FLdDA", "FStart", StaFRR=0, DestP=0)]}, 3.0),
    "a smooth stop mid-move and FBackw": (
        {}, {0.2: [command(1, "FLdVA", "FForw", Veloc=300)], 0.75: [command(1, "FStop", MCW=0x0441B)],
             1.3: [command(1, "FBackw")], 1.6: [command(1, "FStop")]}, 3.0),
    "cyclic reads and the display while the axis moves, a host writing a register": (
        {"h3def": {"fmah3": 48, "bar": 200, "baf": 200, "mna": 1}, "cyclic_reads": ["FRdAP", "FRdSV", "FRdSR"],
         "display": {1: {"reg1": "RActP", "reg2": "RSetV"}}},
        {0.2: [command(1, "FLdAA", "FLdVA", "FLdDA", "FStart", Accel=300, Veloc=120, DestP=180)],
         0.61: [command(1, RActP=7)], 1.1: [command(1, "FLdDA", "FStart", DestP=20)]}, 3.0),
    "cyclic reads of a standing axis beside a moving one": (
        {"cyclic_reads": ["FRdAP", "FRdSV", "FRdITS"], "display": {2: {"reg1": "RActP", "reg2": "RSetV"}}},
        {0.2: [command(1, "FLdAA", "FLdVA", "FLdDA", "FStart", Accel=300, Veloc=150, DestP=250)]}, 4.0),
    "cyclic reads of two axes, the second making a small move": (  # a cycle of 20.8 ms (§10.1)
        {"cyclic_reads": ["FRdAP", "FRdSV", "FRdITS"], "display": {2: {"reg1": "RActP", "reg2": "RSetV"}}},
        {0.2: [command(1, "FLdAA", "FLdVA", "FLdDA", "FStart", Accel=300, Veloc=150, DestP=250)],
         0.9: [command(2, "FLdDA", "FStart", DestP=1)]}, 4.0),
    "the manual's example 3 with I 8 held, then I 15": (
        {"h3def": {"fmah3": 48, "bar": 200, "baf": 200, "mna": 1}, "user_program": "example3"},
        {0.1: [keys(8)], 4.0: [keys(15)]}, 6.0),
    "the manual's example 3 reading RSigB too: a cycle of 10.3 ms, its dwells run out between cycles": (
        {"h3def": {"fmah3": 48, "bar": 200, "baf": 200, "mna": 1}, "user_program": "example3",
         "cyclic_reads": ["FRdSR"]},
        {0.1: [keys(8)]}, 12.0),
}


@pytest.mark.parametrize("name", SCENARIOS)
@pytest.mark.parametrize("seed", [1, 2, 7, 13, 16, 38])
def test_the_skipped_cycles_change_nothing_a_host_sees(name: str, seed: int, monkeypatch: pytest.MonkeyPatch) -> None:
    config, script, seconds = SCENARIOS[name]
    looks, axes, recorded, events = play(config, script, seconds, seed)
    with monkeypatch.context() as patch:
        patch.setattr(model, "quiet_cycles", lambda *_: [])
        every_looks, every_axes, every_recorded, every_events = play(config, script, seconds, seed)
    assert len(looks) == len(every_looks)
    for seen, reference in zip(looks, every_looks, strict=True):
        assert seen == reference
    # the shared axis follows the motor through its position at the chip's last sample, whether
    # a cycle's function (up to the cycle's length after its start) or a host's look computed it:
    # the same line in both, but for the rounding of where it starts
    for seen_axes, reference_axes in zip(axes, every_axes, strict=True):
        assert seen_axes == pytest.approx(reference_axes, rel=1e-12, abs=1e-9)
    assert [name for _, name, *_ in recorded] == [name for _, name, *_ in every_recorded]
    for (when, *what), (reference, *expected) in zip(recorded, every_recorded, strict=True):
        assert what == expected and when == pytest.approx(reference, rel=1e-12, abs=1e-9)
    assert events < every_events


def test_a_moving_axis_wakes_the_plc_only_for_its_events() -> None:
    """FForw at constant velocity for 10 s: about one timer event a second instead of a hundred
    (the look-ahead doubles its reach, up to 0.8 s, while nothing ends it early)."""
    clock = VirtualClock()
    pcd = Pcd4(clock=clock, config={**EXAMPLE, "h3def": {**EXAMPLE["h3def"], "mna": 1}})
    command(1, "FLdAA", "FLdVA", "FForw", Accel=2_000, Veloc=500)(pcd)
    clock.advance(1.0)
    events = clock.advance(10.0)
    pcd.catch_up()
    assert not pcd.drives[0].settled and pcd.drives[0].chip.actual > 500_000
    assert events < 20
    pcd.close()


def test_a_function_late_in_the_cycle_leaves_the_shared_axis_where_the_motor_is() -> None:
    """A PLC cycle's functions act on the chip at their moments (§3.3.2, §10.1: axis 2's reads up
    to 18.9 ms after the start of a cycle of two axes with three reads each), so the chip is
    computed ahead of the clock; the shared axis, on which the switches sit, still passes where
    the motor is now (within a sample's travel), not where it will be then."""
    clock = VirtualClock()
    pcd = Pcd4(clock=clock, config=EXAMPLE)
    command(1, "FLdAA", "FLdVA", "FForw", Accel=2_000, Veloc=500)(pcd)
    clock.advance(1.0)
    pcd.catch_up()
    drive = pcd.drives[0]
    now, before, velocity = clock.now(), drive.motor.position, drive.motor.velocity
    assert velocity > 10_000
    drive.catch_up(now + 0.0189)  # what a function 18.9 ms into the cycle does
    assert drive.motor.position > before + 0.018 * velocity  # the chip is ahead of the clock
    assert drive.axis.position() == pytest.approx(before, abs=velocity * CHIP_SAMPLE)
    pcd.close()
