"""The RMLD attribute byte and the PLC endpoint's framing (spec ip247.md §4.1.2, §3.7; vectors of
§3.6.7 b and c)."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as hs

from devsim.devices.ip247.attributes import AgFramer, ag_frame, rmld


def test_rmld_of_the_profile_vectors() -> None:
    """(b) 02H: metric, not in position, reference set, MD present, running; (c) 86H: metric, in
    position, job finished."""
    assert rmld(unit=1, in_position=False, reference_sync=False, teach_in=False, reference_missing=False,
                md_missing=False, finished=False) == 0x02
    assert rmld(unit=1, in_position=True, reference_sync=False, teach_in=False, reference_missing=False,
                md_missing=False, finished=True) == 0x86
    assert rmld(unit=3, in_position=False, reference_sync=True, teach_in=True, reference_missing=True,
                md_missing=True, finished=True) == 0xF9


@given(messages=hs.lists(hs.tuples(hs.integers(0, 255), hs.binary(max_size=300)), max_size=8),
       cut=hs.integers(min_value=1, max_value=50))
def test_frames_survive_any_cut(messages: list[tuple[int, bytes]], cut: int) -> None:
    stream = b"".join(ag_frame(f, p) for f, p in messages)
    framer = AgFramer()
    got = [m for i in range(0, len(stream), cut) for m in framer.feed(stream[i : i + cut])]
    assert got == messages
