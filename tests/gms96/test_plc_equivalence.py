"""The PLC cycle that leaves out what no rule reads (issue 31: the inputs' PAE when no rule or
hook looks at it, the fault states without message codes, the M function bits when none is set,
the copy rules' bits parsed once, a marker bit read without its byte's other status bits) does what the cycle that takes everything every time does:
two cards, one with that full cycle, fed the same random inputs, marker writes, faults and
moves, show the same markers, outputs, messages, events and cycle count after every step."""

from __future__ import annotations

import math
import random
import types
from typing import Any

import pytest

from devsim.core.clock import VirtualClock
from devsim.core.profile import Segment
from devsim.devices.gms96 import Gms96Device
from devsim.devices.gms96.executor import Cmd
from devsim.devices.gms96.image import parse_bit
from devsim.devices.gms96.io import OUTPUT_BITS
from devsim.devices.gms96.plc import _EPS, M_FUNCTION_BITS, Plc, direction_changes_at


def whole_byte_bit(plc: Plc, name: str) -> bool:
    """A bit as the PLC saw it before issue 31: a marker bit out of the whole byte with its status."""
    area, byte, bit = parse_bit(name)
    if area == "E":
        return bool(plc._pae[byte] >> bit & 1) if byte < len(plc._pae) else False
    if area == "A":
        n = byte * 8 + bit
        if n in plc._paa_writes:
            return plc._paa_writes[n]
        return n < OUTPUT_BITS and plc.outputs.output_bit(n)
    return bool(plc.card.marker_byte(byte) >> bit & 1)


def full_cycle(plc: Plc) -> None:
    """The cycle as it was before issue 31: every part taken every time."""
    plc.cycles += 1
    plc._pae = bytes(plc.outputs.input_byte(b) for b in range(4))
    plc._paa_writes = {}
    ms = plc.cfg.auto_ack_m_functions_ms
    if ms is not None:
        now = plc.now
        for byte, bit in M_FUNCTION_BITS:
            key = (byte, bit)
            if not plc.image.marker(byte, bit):
                plc._ack_seen.pop(key, None)
                continue
            seen = plc._ack_seen.setdefault(key, now)
            if now - seen >= ms / 1000.0 - _EPS:
                del plc._ack_seen[key]
                plc.set_marker_bit(byte, bit, False)
    plc._limit_switches()
    codes = plc.cfg.message_on_fault
    states = plc._fault_states()
    query = plc.image.marker(3, 1)
    if codes is not None:
        for name, active in states.items():
            code = getattr(codes, name)
            if code and active and (query or not plc._faults[name]):
                plc.message(code)
    plc._faults = states
    if query:
        plc.set_marker_bit(3, 1, False)
    plc._start_rules()
    for rule in plc.cfg.copy_bits:
        value = whole_byte_bit(plc, rule.source) != rule.invert
        area, byte, bit = parse_bit(rule.to)
        if area == "A":
            n = byte * 8 + bit
            if n < OUTPUT_BITS and bool(plc.image.outputs[byte] >> bit & 1) != value:
                plc._paa_writes[n] = value
        elif area == "M":
            plc.set_marker_bit(byte, bit, value)
    for hook in plc.hooks:
        hook(plc)
    plc._prev_pae = plc._pae
    plc._flush_paa()


#: Every rule, with the inputs read (limit switches, a start rule, a copy from an input) …
EVERY_RULE = {
    "cycle_ms": 20, "auto_ack_m_functions_ms": 60,
    "limit_switches": [{"input": "E0.3", "action": "stop", "message": 31},
                       {"input": "E0.4", "action": "abort", "direction": "+"}],
    "message_on_fault": {"following_error": 41, "monitoring": 42, "emergency_stop": 43},
    "start_program_on_input": [{"input": "E0.2", "program": 1}],
    "copy_bits": [{"from": "E0.5", "to": "A0.3"}, {"from": "M7.1", "to": "A0.4", "invert": True},
                  {"from": "A0.3", "to": "M20.0"}, {"from": "M1.0", "to": "M21.1"},
                  {"from": "M0.3", "to": "M22.0"}, {"from": "M1.4", "to": "M22.1", "invert": True},
                  {"from": "M1.2", "to": "A0.5"}, {"from": "M0.5", "to": "M22.2"}],
}
#: … and rules that read no input and have no message codes (the parts left out).
NO_INPUTS = {
    "cycle_ms": 20, "auto_ack_m_functions_ms": 60,
    "copy_bits": [{"from": "M1.0", "to": "M0.2"}, {"from": "M7.1", "to": "A0.4", "invert": True},
                  {"from": "A0.4", "to": "M20.0"}, {"from": "M0.3", "to": "M22.0"}, {"from": "M1.4", "to": "A0.5"},
                  {"from": "M0.7", "to": "M22.1"}],
}


#: Every rule but the limit switches.
NO_LIMITS = {key: value for key, value in EVERY_RULE.items() if key != "limit_switches"}
#: Limit rules of each kind (stop and abort, a direction or any, a message, normally closed)
#: on inputs that switches on the axis drive (``AXIS_SWITCHES``) and the random actions set.
LIMITS = {
    "cycle_ms": 20,
    "limit_switches": [{"input": "E0.3", "action": "stop", "message": 31, "direction": "-"},
                       {"input": "E0.4", "action": "abort", "direction": "+"},
                       {"input": "E0.6", "action": "stop", "active_low": True},
                       {"input": "E0.7", "action": "abort", "direction": "-", "message": 32},
                       {"input": "E1.1", "action": "stop", "direction": "+"}],
    "copy_bits": [{"from": "M0.0", "to": "A0.3"}, {"from": "M1.0", "to": "M21.1"}],
}
AXIS_SWITCHES = {"limit_switches": [{"input": "E0.3", "high": -2500}, {"input": "E0.4", "low": 2500},
                                    {"input": "E0.7", "high": -3500}, {"input": "E1.1", "low": 1000, "high": 1200}]}
#: The PLC starting the program again when it ended (the virtual-time benchmark's loop).
LOOPING = {"cycle_ms": 20, "auto_ack_m_functions_ms": 100, "copy_bits": [{"from": "M1.0", "to": "M0.2"}]}


PROGRAM = ["A3000", "m50", "p10;14;2", "p10;16;2", "A0", "m53", "p10;17;2"]


def card(plc: dict[str, Any], full: bool, program: list[str] = PROGRAM) -> Gms96Device:
    axis = AXIS_SWITCHES if plc is LIMITS else {}
    device = Gms96Device(clock=VirtualClock(), config={"boot_time": 0, "plc": plc, "dil": {"address": 3}, "axis": axis})
    if full:
        model = device.model
        model.plc.run_cycle = types.MethodType(full_cycle, model.plc)
    device.set("program.1", program)
    device.model.executor.submit(Cmd("Q", 3, 0, 0, 1))
    return device


def seen(device: Gms96Device) -> tuple[Any, ...]:
    m = device.model
    return (bytes(m.image.markers), bytes(m.image.outputs), tuple(m.image.pending_messages), m.plc.cycles,
            [e for _t, e in m.events], m.plc._ack_seen, [m.marker_byte(b) for b in (0, 1, 3)],
            m.axis.position(), len(m.executor.queue))


ACTIONS = (
    lambda d, r: d.set(f"input.E{r.choice((0, 1, 2))}.{r.randrange(8)}", r.random() < 0.5),
    lambda d, r: d.set(f"input.E0.{r.choice((2, 3, 4, 5))}", r.random() < 0.5),
    lambda d, r: d.set(f"marker.M{r.choice((6, 7, 8, 10, 15, 18))}.{r.randrange(8)}", r.random() < 0.7),
    lambda d, r: d.set("marker.M3.1", True),
    lambda d, r: d.set("marker.MB2", 1),
    lambda d, r: d.set("marker.M0.2", True),
    lambda d, r: d.set("input.emergency_stop", r.random() < 0.2),
    lambda d, r: d.set("quantity.monitoring", r.choice(("", "", "dc_undervoltage"))),
    lambda d, r: d.model.executor.submit(Cmd("Q", 3, 0, 0, 1)),
    lambda d, r: d.model.executor.submit(Cmd("A", r.randrange(-4000, 4000), 0, 0, 1)),
    lambda d, r: d.set("marker.M0.1", True),
    lambda d, r: d.set(f"input.E{r.choice((0, 1))}.{r.choice((1, 3, 4, 6, 7))}", r.random() < 0.5),
    lambda d, r: d.model.executor.submit(Cmd("v", r.randrange(-3000, 3000), 0, 0, 1)),
    lambda d, r: d.set("marker.M0.0", r.random() < 0.3),
)


@pytest.mark.parametrize("rules", [EVERY_RULE, NO_INPUTS], ids=["every_rule", "no_inputs"])
@pytest.mark.parametrize("seed", range(6))
def test_the_lean_cycle_does_what_the_full_cycle_does(rules: dict[str, Any], seed: int) -> None:
    lean, full = card(rules, False), card(rules, True)
    r = random.Random(seed)
    for _step in range(400):
        if r.random() < 0.3:
            action, value = r.choice(ACTIONS), r.random()
            for device in (lean, full):
                action(device, random.Random(value))
        dt = r.choice((0.001, 0.007, 0.02, 0.05, 0.3))
        for device in (lean, full):
            device.model.clock.advance(dt)
        assert seen(lean) == seen(full)
    assert lean.model.plc.cycles > 1000


@pytest.mark.parametrize("rules", [EVERY_RULE, NO_LIMITS, NO_INPUTS, LOOPING, LIMITS],
                         ids=["every_rule", "no_limits", "no_inputs", "looping", "limits"])
@pytest.mark.parametrize("seed", range(8))
def test_cycles_skipped_while_nobody_looks_change_nothing(rules: dict[str, Any], seed: int) -> None:
    """While nobody looks (a scenario waits for its next step), the PLC skips the cycles that
    would read what the last one read and change nothing (issue 31): between the looks and the
    actions the card is the card that ran every cycle, the cycle count included; limit rules
    too, whose inputs switches on the axis drive at their solved instants (timers the skip
    waits for) and whose direction changes at the plan's boundaries."""
    lean, full = card(rules, False), card(rules, True)
    full.model.plc._schedule_next = full.model.plc._schedule  # (every cycle, one by one)
    r = random.Random(seed)
    skipped = 0
    for _step in range(150):
        if r.random() < 0.4:
            action, value = r.choice(ACTIONS), r.random()
            for device in (lean, full):
                action(device, random.Random(value))
        dt = r.choice((0.001, 0.02, 0.05, 0.3, 1.0, 4.0))
        lean.unobserved_until(lean.model.clock.now() + dt)
        events = lean.model.clock.advance(dt)
        skipped += full.model.clock.advance(dt) - events
        lean.unobserved_until(-math.inf)
        assert seen(lean) == seen(full)
    assert skipped > 1000  # (cycles the lean card did not run one by one)


def test_a_cycle_at_the_instant_of_another_timer_still_runs_after_it() -> None:
    """Times on a binary grid (a 250 ms cycle, 0.5 s waits, no moves): a wait of the program ends
    at the very instant of a cycle, and the cycle (scheduled after the wait) runs after it and
    sees its output, as the cycles one by one do; a skip that took that cycle too would not."""
    rules = {"cycle_ms": 250, "auto_ack_m_functions_ms": 250,
             "copy_bits": [{"from": "M1.0", "to": "M0.2"}, {"from": "A0.2", "to": "M20.0"}]}
    program = ["m50", "p10;14;5", "p10;16;2", "m53", "p10;14;5", "p10;17;2", "p10;14;5"]
    lean, full = card(rules, False, program), card(rules, True, program)
    full.model.plc._schedule_next = full.model.plc._schedule
    for device in (lean, full):
        device.model.clock.advance(1.0)
        device.set("marker.MB2", 1)
        device.set("marker.M0.2", True)
    marks = []
    for _step in range(40):
        lean.unobserved_until(lean.model.clock.now() + 1.0)
        lean.model.clock.advance(1.0)
        full.model.clock.advance(1.0)
        lean.unobserved_until(-math.inf)
        assert seen(lean) == seen(full)
        marks.append(lean.read("marker.M20.0"))
    assert True in marks and False in marks  # the loop ran, its output copied on and off


def test_a_looping_program_is_not_cycled_one_by_one_while_nobody_looks() -> None:
    """The looping program of ``benchmarks/virtual.py``: the copy rule M1.0 -> M0.2 writes 0 to
    M0.2 every cycle while the program runs, which changes nothing (manual §2.4.1: 'w: Starte
    CNC Programm'; the card clears M0.2 when the program ends), so those cycles are skipped while
    nobody looks, and the card is the card that ran every cycle (a write the card took without a
    change counted as one made every cycle run one by one: 183,116 timers in the benchmark's hour
    instead of 8,329)."""
    lean, full = card(LOOPING, False), card(LOOPING, True)
    full.model.plc._schedule_next = full.model.plc._schedule
    for device in (lean, full):
        device.model.clock.advance(0.5)
        device.set("marker.MB2", 1)
        device.set("marker.M0.2", True)
    ran = cycles = 0
    programs = set()
    for _step in range(30):
        before = lean.model.plc.cycles
        lean.unobserved_until(lean.model.clock.now() + 2.0)
        ran += lean.model.clock.advance(2.0)
        full.model.clock.advance(2.0)
        lean.unobserved_until(-math.inf)
        assert seen(lean) == seen(full)
        cycles += lean.model.plc.cycles - before
        programs.add(lean.model.axis.position())
    assert len(programs) > 1  # (the program ran, moving the axis)
    assert cycles >= 2900 and ran < cycles / 5


def plan(target: float | None, *segments: Segment, jog: int = 0) -> Any:
    """An indexer as :func:`direction_changes_at` reads it: the target, the jog, the plan."""
    def state(t: float | None, part: str) -> float:
        seg = next(seg for seg in segments if seg.t0 <= t <= seg.t1)
        return getattr(seg, part)(t)

    axis = types.SimpleNamespace(segments=lambda: list(segments), position=lambda t=None: state(t, "position"),
                                 velocity=lambda t=None: state(t, "velocity"))
    return types.SimpleNamespace(target=target, jog_dir=jog, axis=axis)


@pytest.mark.parametrize(("indexer", "change"), [
    # braking from 2000 inc/s at 4000 inc/s² over a target 400 inc ahead (it turns 500 inc on, at 0.5 s)
    (plan(400.0, Segment(0.0, 1.0, 0.0, 2000.0, -4000.0)), (1 - math.sqrt(1 - 0.8)) / 2),  # 2000 t - 2000 t² = 400
    (plan(None, Segment(0.0, 1.0, 0.0, 2000.0, -4000.0)), 0.5),  # no target: the velocity turns at 0.5 s
    (plan(2000.0, Segment(0.0, math.inf, 0.0, 1000.0, 0.0)), 2.0),  # an endless cruise reaches the target
    (plan(-50.0, Segment(0.0, 1.0, 0.0, 500.0, 0.0)), None),  # moving away from it
    (plan(None, Segment(0.0, 1.0, 0.0, 2000.0, -4000.0), jog=-1), None),  # a jog: its direction
    (plan(300.0), None),  # at rest
])
def test_the_skip_waits_for_the_commanded_direction_to_change(indexer: Any, change: float | None) -> None:
    """A limit rule with a direction reads where the set-point goes: a skip ends at or just
    before the moment that changes inside a segment (the set-point passing the target, the
    velocity turning), and not before where it does not."""
    until = math.inf  # (nobody looks for ever, no other timer)
    at = direction_changes_at(indexer, 0.0, until)
    if change is None:
        assert at == until
        return
    assert change - 1e-8 <= at <= change
