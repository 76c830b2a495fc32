"""Walk of manual §4.3.11–§4.3.16 (machine data input, delete, read) and §2.5 where the record's
items act, driven through the PG port on a real pty."""

from __future__ import annotations

import pytest

from tests.ip247.helpers import START, Module, record
from tests.ip247.test_machine_data import COM247, words

REFERENCE_MISSING = 0x20  # §2.7 attribute bit 5


def rewrite(mod: Module, hex_words: str = COM247) -> bytes:
    """BA20 again on axis 1 with the PG's overwrite flag (COM247 asks "Maschinendaten überschreiben ?")."""
    data = words(hex_words)
    data[3] = (data[3] & 0xFF00) | 1
    return mod.write(1, 20, 101, data, flags=1)


def reference_missing(mod: Module) -> bool:
    return bool(mod.call(0x62, b"\x01")[6] & REFERENCE_MISSING)


@pytest.mark.manual("§4.3.12", "after a new input of machine data the reference point is not lost when the "
                    "relevant items of the new record equal the old one's")
def test_identical_machine_data_keep_the_reference(mod: Module) -> None:
    mod.ready()
    assert not reference_missing(mod)
    assert rewrite(mod)[8] == 0
    assert not reference_missing(mod)
    assert mod.operate(1, 6, START, w=1000, dd=2_000)[4] == 0  # an absolute target is still allowed


@pytest.mark.manual("§4.3.12", "items the manual does not name as relevant (here the software limit switch "
                    "Ende and the jog velocity) may change without losing the reference point")
def test_items_not_named_keep_the_reference(mod: Module) -> None:
    mod.ready()
    assert rewrite(mod, record(limit_end=400_000, jog1=500))[8] == 0
    assert not reference_missing(mod)


@pytest.mark.parametrize("changes", [
    {"reference": 2_000}, {"pulses_per_rev": 900}, {"gear": 1_000},
    {"reference_direction": 0x00}, {"reference_sync": 0},
], ids=["reference coordinate", "pulses per revolution", "travel per revolution", "reference direction",
        "synchronisation"])
@pytest.mark.manual("§4.3.12", "the relevant items are the reference coordinate, pulses per revolution, travel "
                    "per revolution, reference direction and synchronisation: a change of one loses the "
                    "reference point")
def test_a_relevant_item_changed_loses_the_reference(mod: Module, changes: dict) -> None:
    mod.ready()
    assert rewrite(mod, record(**changes))[8] == 0
    assert reference_missing(mod)
    assert mod.operate(1, 6, START, w=1000, dd=2_000)[4] == 10  # "Referenzpunkt fehlt"


@pytest.mark.manual("§4.3.12", "deleting a machine-data record leaves the reference point set in the "
                    "attributes; entering the same data again keeps it")
def test_delete_then_the_same_record_keeps_the_reference(mod: Module) -> None:
    mod.ready()
    assert mod.client.delete_record(1, 21, 101)[:5] == bytes((0, 1, 21, 0, 0))  # BA21 on axis 1
    assert mod.call(0x62, b"\x01")[6] & 0x40  # machine data missing (bit 6) ...
    assert not reference_missing(mod)  # ... the reference point still set
    assert mod.load_md()[8] == 0
    assert not reference_missing(mod)


@pytest.mark.manual("§4.3.12", "zero offsets and tool offsets are reset at every machine-data input")
def test_md_input_resets_the_offsets(mod: Module) -> None:
    mod.ready()
    assert mod.operate(1, 13, 3, dd=4_000)[4] == 0  # BA13 origin 4 mm forward
    assert mod.operate(1, 15, 3, dd=3_000)[4] == 0  # BA15 tool 3 mm forward
    assert mod.device.read("axis.1.position") == 1_000 - 4_000 + 3_000
    assert rewrite(mod)[8] == 0
    assert mod.device.read("axis.1.position") == 1_000
