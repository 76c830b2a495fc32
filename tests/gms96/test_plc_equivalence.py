"""The PLC cycle that leaves out what no rule reads (issue 31: the inputs' PAE when no rule or
hook looks at it, the fault states without message codes, the M function bits when none is set,
the copy rules' bits parsed once, a marker bit read without its byte's other status bits) does what the cycle that takes everything every time does:
two cards, one with that full cycle, fed the same random inputs, marker writes, faults and
moves, show the same markers, outputs, messages, events and cycle count after every step."""

from __future__ import annotations

import random
import types
from typing import Any

import pytest

from devsim.core.clock import VirtualClock
from devsim.devices.gms96 import Gms96Device
from devsim.devices.gms96.executor import Cmd
from devsim.devices.gms96.image import parse_bit
from devsim.devices.gms96.io import OUTPUT_BITS
from devsim.devices.gms96.plc import _EPS, M_FUNCTION_BITS, Plc


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


def card(plc: dict[str, Any], full: bool) -> Gms96Device:
    device = Gms96Device(clock=VirtualClock(), config={"boot_time": 0, "plc": plc, "dil": {"address": 3}})
    if full:
        model = device.model
        model.plc.run_cycle = types.MethodType(full_cycle, model.plc)
    device.set("program.1", ["A3000", "m50", "p10;14;2", "p10;16;2", "A0", "m53", "p10;17;2"])
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
