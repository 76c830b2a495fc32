"""An IP247 axis's zero and tool offsets (spec ip247.md §5.9, §4.11.6, §4.11.7; vectors §5.9,
§6.6, §6.7)."""

from __future__ import annotations

from devsim.devices.ip247.coordinates import Coordinates

MM = 1000  # base units per mm


def test_the_zero_offset_program_of_section_6_6() -> None:
    """Holder H and reported actual A step by step (ZO1 40, ZO2 80, ZO3 120 mm)."""
    c = Coordinates(limit_begin=-1_000 * MM, limit_end=1_000 * MM, reference=0)
    assert c.actual(0) == 0
    assert c.shift(10 * MM, forward=True) is None and c.actual(0) == -10 * MM
    holder = c.holder_for(0)
    assert holder == 10 * MM
    assert [c.actual(h * MM) for h in (10, 20, 30, 50)] == [0, 10 * MM, 20 * MM, 40 * MM]
    c.program_shift(40 * MM)  # N3 G54
    assert [c.actual(h * MM) for h in (50, 60, 70, 90)] == [0, 10 * MM, 20 * MM, 40 * MM]
    c.program_shift(80 * MM)  # N6 G55 replaces G54
    assert [c.actual(h * MM) for h in (90, 100, 110, 130)] == [0, 10 * MM, 20 * MM, 40 * MM]
    c.program_shift(120 * MM)  # N9 G56
    assert c.actual(0) == -130 * MM  # N10 G74: the holder at the reference point
    c.program_end()
    assert c.actual(0) == -10 * MM  # the BA13 shift remains


def test_the_tool_offset_example_of_section_5_9_and_the_program_table() -> None:
    c = Coordinates(limit_begin=-1_000 * MM, limit_end=1_000 * MM, reference=0)
    assert c.holder_for(50 * MM) == 50 * MM
    assert c.set_tool(100 * MM, forward=True) is None and c.holder_for(200 * MM) == 100 * MM
    c.clear_tools()
    assert c.holder_for(50 * MM) == 50 * MM
    # §4.11.6: MD tool correction 10 mm; BA15 100 forward, then G44 twice: 90, 80; new BA15 200: 200
    c.set_tool(100 * MM, forward=True)
    c.program_tool(10 * MM, positive=False)
    assert c.tool_offset == 90 * MM
    c.program_tool(10 * MM, positive=False)
    c.program_end()
    assert c.tool_offset == 80 * MM
    c.set_tool(200 * MM, forward=True)
    assert (c.to_ba15, c.to_prog) == (200 * MM, 0)


def test_limits_of_offsets() -> None:
    c = Coordinates(limit_begin=-400 * MM, limit_end=500 * MM, reference=0)
    assert c.set_actual(0, 100_000_000) == 62
    assert c.shift(99_700 * MM, forward=True) == 23 and c.zo_mode == 0
    assert c.set_tool(99_600 * MM, forward=True) == 23


def test_rotary_vectors_of_section_6_7() -> None:
    """BA12 at 60° with 400° → actual 400°, range 340° … 700°; BA15 30° forward at 60° → 90°,
    range still 0° … 360°; a tool offset as large as the range is error 63."""
    deg = 1000
    c = Coordinates(limit_begin=0, limit_end=360 * deg, reference=0, rotary=True)
    assert c.set_actual(60 * deg, 400 * deg) is None
    assert c.actual(60 * deg) == 400 * deg and c.range() == (340 * deg, 700 * deg)
    r = Coordinates(limit_begin=0, limit_end=360 * deg, reference=0, rotary=True)
    assert r.set_tool(30 * deg, forward=True) is None
    assert r.actual(60 * deg) == 90 * deg and r.range() == (0, 360 * deg)
    assert r.set_tool(360 * deg, forward=True) == 63
