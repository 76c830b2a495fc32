"""The IP247's program memory (spec ip247.md §4.10)."""

from __future__ import annotations

import pytest

from devsim.devices.ip247.store import CAPACITY, ProgramStore, Stored, StoreError

BEISPIEL = "%  1 BEISPIEL\nN1 X100 F1000 M10\nN2 M02\n"


def test_storage_order_directory_and_refusals() -> None:
    store = ProgramStore()
    store.add(Stored(78, "%078\nN1 M02\n"), from_plc=True)
    store.add(Stored(1, BEISPIEL), from_plc=True)
    assert store.directory() == [(78, 11), (1, 25)]  # storage order; the manual's example: 25 words
    with pytest.raises(StoreError) as plc:
        store.add(Stored(1, BEISPIEL), from_plc=True)
    with pytest.raises(StoreError) as pg:
        store.add(Stored(1, BEISPIEL), from_plc=False)
    with pytest.raises(StoreError) as full:
        store.add(Stored(2, "x" * (CAPACITY - store.used + 1)), from_plc=True)
    assert (plc.value.error, pg.value.error, full.value.error) == (49, 20, 24)


def test_deleting_compacts_unless_a_program_runs() -> None:
    """§4.10 / error 61: while another program executes, a delete only leaves the directory and
    the characters stay counted; a running program cannot be deleted (51)."""
    store = ProgramStore()
    for number in (1, 2, 3):
        store.add(Stored(number, BEISPIEL), from_plc=True)
    used = store.used
    assert store.delete(2, executing=set()) == 0 and store.used == used - len(BEISPIEL)
    assert store.delete(3, executing={1}) == 61 and store.used == used - len(BEISPIEL)
    with pytest.raises(StoreError) as running:
        store.delete(1, executing={1})
    assert running.value.error == 51
    assert ProgramStore.from_json(store.to_json()).used == store.used
    store.add(Stored(4, BEISPIEL), from_plc=True)
    assert store.delete(4, executing=set()) == 0 and store.used == len(BEISPIEL)  # the gap is closed too
    assert ProgramStore.from_json(store.to_json()).directory() == store.directory() == [(1, 25)]


def test_255_programs_at_most() -> None:
    store = ProgramStore([Stored(n, "%\nN1 M02\n") for n in range(255)])
    with pytest.raises(StoreError) as full:
        store.add(Stored(255, "%\nN1 M02\n"), from_plc=True)
    assert full.value.error == 18
