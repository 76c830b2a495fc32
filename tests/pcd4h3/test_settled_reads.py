"""A read changes no chip (issue 31, "sampled loops only while they matter"; spec pcd4h3.md
§3.5.3: the report commands RDRP, RDDP, RDRV, RDDV, RDSUM, RDIP, RDSIGS only read): a standing
axis whose PLC reads it every cycle (cyclic reads, the manual's Examples 2 and 3) counts as
settled, as one that nobody reads does, so its samples are no longer computed while the PLC
cycles.  A host sees what it saw while the chip was sampled one by one without rest: every
register and flag, the S-Bus answers (the diagnostics block included), the display, the chip
trace, the recorded events, at random looks; and far fewer samples are computed."""

from __future__ import annotations

import copy
import math
import random
from typing import Any

import pytest

from devsim.core.clock import VirtualClock
from devsim.devices.pcd4h3 import batch, model, stepper
from devsim.devices.pcd4h3.batch import STILL
from devsim.devices.pcd4h3.config import READ_FUNCTIONS
from devsim.devices.pcd4h3.library import TIMES
from devsim.devices.pcd4h3.lm628 import Lm628
from devsim.devices.pcd4h3.model import Pcd4
from devsim.devices.pcd4h3.pid import Motor
from devsim.devices.pcd4h3.services import read
from tests.pcd4h3.helpers import Step, blocked, command, keys

ONE_AXIS = {"h3def": {"fmah3": 48, "bar": 200, "baf": 200, "mna": 1}, "modules": 1, "variant": "H320",
            "response_delay_ms": 0}


def look(pcd: Pcd4) -> tuple[Any, ...]:
    """What a host sees now: the media as S-Bus reads them (the axis's block and its
    diagnostics), every flag, the display, the chip trace, the PLC's state."""
    pcd.catch_up()
    axis = pcd.axes[0]
    block = [pcd.layout.block(1) + offset for offset in range(20)]
    diagnostics = [pcd.diag_registers + offset for offset in range(15)]
    registers = tuple(read(pcd, "register", address) for address in (*block, *diagnostics))
    flags = tuple(read(pcd, "flag", address) for address in sorted({*pcd.flags, pcd.diag_flags + 2}))
    return (pcd.clock.now(), registers, flags, sorted(pcd.screens.items()), pcd.status, pcd.handler_calls(),
            axis.transfers, tuple(axis.trace[-40:]), pcd.drives[0].chip.status)


def play(config: dict[str, Any], script: dict[float, list[Step]], seconds: float, seed: int
         ) -> tuple[list[Any], list[str], int]:
    """The script's steps at their times and looks at random moments between them; returns
    the looks, the recorded events and the samples computed."""
    clock = VirtualClock()
    pcd = Pcd4(clock=clock, config={**ONE_AXIS, **config})
    computed = [0]
    run = batch._run

    def counting(chip: Any, count: int, quiet: int, marks: list[int], checkpoints: list[Any], *more: Any) -> int:
        quiet = run(chip, count, quiet, marks, checkpoints, *more)
        computed[0] += checkpoints[-1][0] if marks and checkpoints else count
        return quiet

    rng = random.Random(seed)
    moments = sorted({*script, *(round(rng.uniform(0, seconds), 6) for _ in range(60))})
    looks = []
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(batch, "_run", counting)
        for moment in [*moments, seconds]:
            clock.advance_to(moment)
            for step in script.get(moment, ()):
                step(pcd)
            looks.append(look(pcd))
    pcd.close()
    return looks, [str(event) for event in pcd.events], computed[0]


SCENARIOS: dict[str, tuple[dict[str, Any], dict[float, list[Step]], float]] = {
    "every read function, a move, a stand, a move back": (
        {"cyclic_reads": list(READ_FUNCTIONS), "display": {1: {"reg1": "RActP", "reg2": "RSetV"}}},
        {0.2: [command(1, "FLdAA", "FLdVA", "FLdDA", "FSetIP", "FStart", Accel=300, Veloc=120, DestP=180)],
         3.5: [command(1, "FLdDA", "FStart", DestP=20)], 5.2: [command(1, RActP=7)]}, 9.0),
    "a blocked motor's integral winds up slowly, read every cycle, then it turns": (
        {"cyclic_reads": ["FRdITS", "FRdAP", "FRdSR"]},
        {0.2: [blocked(1, True), command(1, "FLdRP", "FUpDRP", "FLdDA", "FStart", KInt=1, DestP=1)],
         2.5: [blocked(1, False)]}, 5.0),
    "a weak P-only loop rests off its target (Σe grows), then an integral term acts": (
        {"cyclic_reads": ["FRdITS", "FRdAP", "FRdSP"]},
        {0.2: [command(1, "FLdRP", "FUpDRP", "FLdDA", "FStart", KProp=9, KInt=0, KDer=0, DestP=1)],
         3.0: [command(1, "FLdRP", "FUpDRP", KProp=150, KInt=50, KDer=50)]}, 5.0),
    "the manual's example 2 with I 8 held": (
        {"user_program": "example2"}, {0.1: [keys(8)]}, 12.0),
    "the manual's example 3 with I 8 held, then I 15": (
        {"user_program": "example3"}, {0.1: [keys(8)], 14.0: [keys(15)]}, 18.0),
}


@pytest.mark.parametrize("name", SCENARIOS)
@pytest.mark.parametrize("seed", [1, 5])
def test_a_standing_axis_read_every_cycle_rests_and_a_host_sees_the_same(name: str, seed: int) -> None:
    config, script, seconds = SCENARIOS[name]
    looks, events, computed = play(config, script, seconds, seed)
    with pytest.MonkeyPatch.context() as patch:  # the reference: every sample computed, every cycle run
        patch.setattr(stepper, "QUIET", 1 << 62)
        patch.setattr(model, "quiet_cycles", lambda *_: [])
        every_looks, every_events, every_computed = play(config, script, seconds, seed)
    assert len(looks) == len(every_looks)
    for seen, reference in zip(looks, every_looks, strict=True):
        assert seen == reference
    assert events == every_events
    assert computed < every_computed or name.startswith("the manual's example 3")  # (its looks-ahead recompute)


def test_a_standing_axis_read_every_cycle_computes_no_samples(monkeypatch: pytest.MonkeyPatch) -> None:
    """Ten seconds of a standing axis that the PLC reads with every read function each cycle:
    the cycles read (every read in every cycle, in the trace, as a look finds them), no sample
    is computed, and the PLC wakes about once a second (the cycles between only read what
    stays: they run when someone looks)."""
    clock = VirtualClock()
    pcd = Pcd4(clock=clock, config={**ONE_AXIS, "cyclic_reads": list(READ_FUNCTIONS)})
    command(1, "FLdDA", "FStart", DestP=30)(pcd)
    clock.advance(3.0)  # the move and the motor's last hunting
    pcd.catch_up()  # (a look: the cycles skipped so far run their reads)
    assert pcd.drives[0].settled
    axis, computed = pcd.axes[0], [0]
    run = batch._run

    def counting(chip: Any, count: int, quiet: int, marks: list[int], checkpoints: list[Any], *more: Any) -> int:
        computed[0] += count
        return run(chip, count, quiet, marks, checkpoints, *more)

    monkeypatch.setattr(batch, "_run", counting)
    transfers = axis.transfers
    events = clock.advance(10.0)
    pcd.catch_up()
    assert events < 20
    assert pcd.drives[0].settled and axis.registers.actual_position == 30  # user units
    assert computed == [0]
    cycle = max(0.010, (0.5 + sum(TIMES[symbol] for symbol in READ_FUNCTIONS)) / 1000)  # §3.3.2, §10.1
    assert axis.transfers - transfers == pytest.approx(10.0 / cycle * len(READ_FUNCTIONS), abs=len(READ_FUNCTIONS))
    assert axis.trace[-1][0] == "RDSIGS"
    pcd.close()


def settled_chip(pid: tuple[int, int, int, int, int], target: int) -> tuple[Lm628, int]:
    """An LM628 (the batch tests' motor) that moved to ``target`` and settled: its quiet count."""
    chip = Lm628(Motor())
    chip.reset()
    chip.port(12)
    kp, ki, kd, il, ds = pid
    chip.load_filter(ds << 8 | 0x0F, [kp, ki, kd, il])
    chip.update_filter()
    chip.command("LTRJ", 0x002A, 76, 1_117_389, target)
    chip.command("STT")
    quiet = 0
    for _ in range(200_000):
        quiet = batch.run_reference(chip, 1, quiet)
        if quiet >= stepper.QUIET:
            return chip, quiet
    raise AssertionError("the chip did not settle")


def integers(chip: Lm628) -> tuple[Any, ...]:
    """Everything of the chip but the motor's floating point."""
    state = batch.snapshot(chip)
    return (*state[:11], *state[13:], chip.actual, chip.status, chip.signals)


@pytest.mark.parametrize(("pid", "target"), [
    ((150, 50, 50, 500, 15), 3_000),  # the manual's registers (Example 1)
    ((5, 0, 0, 0, 3), 2_000),  # a weak P-only loop: it rests two counts off, Σe grows without an integral term
    ((150, 50, 50, 500, 255), -1_500),  # the longest derivative interval
])
@pytest.mark.parametrize("count", [1, 17, 256, 5_000])
def test_a_settled_chips_samples_in_closed_form_are_those_one_by_one(pid: tuple[int, int, int, int, int],
                                                                      target: int, count: int) -> None:
    chip, quiet = settled_chip(pid, target)
    reference = copy.deepcopy(chip)
    assert batch.rest(chip, count)
    assert batch.run_reference(reference, count, quiet) == quiet + count  # nothing changed
    assert integers(chip) == integers(reference)
    assert chip.motor.position == pytest.approx(reference.motor.position, rel=0, abs=1e-9)
    assert chip.motor.velocity == pytest.approx(reference.motor.velocity, rel=1e-9, abs=1e-300)


def test_a_weak_loop_rests_off_its_target() -> None:
    """(The case the closed form's Σe is for.)"""
    chip, _ = settled_chip((5, 0, 0, 0, 3), 2_000)
    assert chip.desired - chip.actual == 2


def test_the_closed_form_leaves_a_chip_it_cannot_rest_unchanged() -> None:
    """A load the output does not hold exactly, a lag that would reach the next count: the
    samples are the caller's to compute."""
    chip, _ = settled_chip((150, 50, 50, 500, 15), 3_000)
    chip.motor.load = 1e-6
    before = batch.snapshot(chip)
    assert not batch.rest(chip, 100)
    assert batch.snapshot(chip) == before
    chip.motor.load = 0.0
    chip.rest_x = math.floor(chip.motor.position) + 5e-6  # where its rest began; the lag: τ·|v| = 1e-5 counts
    chip.rest_v, chip.rest_n = -STILL / 2, 0
    before = batch.snapshot(chip)
    assert not batch.rest(chip, 100)
    assert batch.snapshot(chip) == before
    assert batch.rest(chip, 1)  # one sample's lag stays within the count
