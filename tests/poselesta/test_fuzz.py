"""Garbage never crashes the POSELESTA's tape reader and never touches programs other than the
one a read-in is going into (spec §3.5; issue: "garbage on every port never damages stored
programs")."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as hs

from devsim.core.clock import VirtualClock
from devsim.core.nvram import NonVolatileMemory
from devsim.devices.poselesta import PoselestaDevice
from devsim.devices.poselesta.codes import encode
from devsim.devices.poselesta.tape import BlockRead, Ended, Failed, TapeReader

PIECES = [b"%", b"\r", b"\n", b"N1", b"N 999", b"X", b"-", b"12.5", b"C", b"#", b"M30", b"M02", b"G1",
          b"\x00", b"\x7f", b"(", b".", b"Y-0.001", b"F9999", b"L99.999", b"Z1234.567"]


@settings(max_examples=300, deadline=None)
@given(data=hs.lists(hs.one_of(hs.sampled_from(PIECES), hs.binary(max_size=8)), max_size=60), iso=hs.booleans())
def test_reader_takes_anything_and_chunks_do_not_matter(data: list[bytes], iso: bool) -> None:
    stream = b"".join(encode(p.decode("latin-1"), iso) if p.isascii() else p for p in data)
    whole = TapeReader(iso=iso).feed(stream)
    reader = TapeReader(iso=iso)
    pieces = [event for i in range(len(stream)) for event in reader.feed(stream[i : i + 1])]
    assert pieces == whole
    ends = [e for e in whole if isinstance(e, Ended | Failed)]
    assert len(ends) <= 1 and (not ends or whole[-1] is ends[0])  # nothing after the end
    assert all(0 <= e.block.number <= 999 for e in whole if isinstance(e, BlockRead))


@settings(max_examples=100, deadline=None)
@given(noise=hs.lists(hs.tuples(hs.sampled_from(["v6", "v7", "v8"]), hs.binary(max_size=64)), max_size=20))
def test_garbage_on_every_port_leaves_other_programs_alone(noise: list[tuple[str, bytes]]) -> None:
    clock = VirtualClock()
    nvram = NonVolatileMemory(None)
    device = PoselestaDevice(clock=clock, config={"boot_time": 0}, nvram=nvram)
    device.set("program.P01", "N1 X1\nN2 Y2")
    kept = nvram.get("programs")["1"]
    device.set("panel.mode", "EXTERNAL_OPERATION")
    device.set("panel.program", 5)
    device.set("v7.transfer", "input")
    for port, data in noise:
        device.port(port).feed(data)
        clock.advance(0.05)
    assert nvram.get("programs")["1"] == kept
    assert device.read("program.P01") == "N 1 X 1.000\nN 2 Y 2.000"


INPUTS = ["nc_start", "nc_stop", "emergency_stop", "axis_enable", "program_continue", "tool_change_ack",
          "m10_ack", "mst_ack", "block_skip_cancel", "block_abort", "optional_stop", "jog_pos_x", "jog_neg_y",
          "jog_step_100", "rapid", "handwheel_x", "open_loop", "inch", "limit_pos_x", "limit_neg_y", "rm_enable_x"]
ACTIONS = [
    *(("input." + name, value) for name in INPUTS for value in (True, False)),
    *(("panel.mode", mode) for mode in ("MANUAL", "AUTO_CONTINUOUS", "AUTO_SINGLE_BLOCK", "MANUAL_SINGLE_BLOCK",
                                         "PROGRAM_ENTRY", "EXTERNAL_OPERATION")),
    ("panel.nc_start", True), ("panel.reference", "x"), ("handwheel.turn", 7), ("axis.x.push", 1.0),
    ("input.override_pot_v", 0.0), ("input.override_pot_v", 10.0), ("input.feed_pot_v", 2.5),
    ("panel.mdi", "N1 G01 X5 F500"), ("panel.program", 1), ("panel.program", 2), ("param.P9", 20),
    ("diagnostics.output_test", True), ("diagnostics.output_test", False), ("panel.diagnostic", 3),
]
PROGRAM = ("N1 G00 X10 Y5 M03 S1250 T07\nN2 G01 X20 F3000\nN3 G02 X30 Y15 I20 J15\nN4 G03 X20 Y5 I20 J15 M06\n"
           "N5 M10 X0 #\nN6 G04 L0.5 M00\nN7 G12 L2.100\nN8 M02\nN100 G91 X1\nN101 G13 L1.100\nN102 G11")


@settings(max_examples=150, deadline=None)
@given(steps=hs.lists(hs.tuples(hs.sampled_from(ACTIONS), hs.floats(min_value=0, max_value=1.5)), max_size=40))
def test_any_operator_and_machine_sequence_keeps_the_control_sane(steps: list[tuple[tuple[str, object], float]]) -> None:
    """Any order of inputs, panel actions and waits: only refusals (BadValue), never a crash;
    the stored programs stay; positions stay finite; the state is one of the declared ones."""
    from devsim.core.points import BadValue
    from devsim.devices.poselesta.execution import STATES

    clock = VirtualClock()
    nvram = NonVolatileMemory(None)
    device = PoselestaDevice(clock=clock, config={"boot_time": 0}, nvram=nvram)
    device.set("program.P01", PROGRAM)
    device.set("program.P02", "N1 G01 X-5 Y-5 F100")
    kept = dict(nvram.get("programs"))
    device.set("panel.program", 1)
    device.set("panel.mode", "AUTO_CONTINUOUS")
    device.set("panel.nc_start", True)  # the program runs while the sequence arrives
    for (name, value), wait in steps:
        try:
            device.set(name, value)
        except BadValue:
            pass
        clock.advance(wait)
        assert device.read("program.state") in STATES
        for axis in "xyzd":
            position = device.read(f"axis.{axis}.position")
            assert position == position and abs(position) < 1e9  # finite
    clock.advance(30.0)
    assert nvram.get("programs") == kept
