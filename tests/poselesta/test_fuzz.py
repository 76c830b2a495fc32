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
