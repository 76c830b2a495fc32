"""How a DNC read-in (T7) ends and what it leaves in the program memory, through the real V7 pty
(manual §2.6, §2.6.3; spec poselesta.md §3.5.1, §3.5.3, §4.9): a block that cannot be stored ends
the transfer there whatever way the host's bytes were cut into writes, a program nothing could
be stored in is not listed, and a tape's blocks reach the non-volatile memory together, not one
whole-memory save per block."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest

from devsim.devices.poselesta.codes import encode
from devsim.devices.poselesta.transfers import ReadIn
from tests.poselesta.test_manual_serial import await_tape, bytes_in
from tests.poselesta.test_ports import open_port, until

FULL = "WERTBEREICHES-UEBERLAUF"


@pytest.fixture
def cnc(devsim_device: Any) -> Any:
    return devsim_device("poselesta")


def _send(cnc: Any, blocks: list[str], *, one_write: bool) -> None:
    """The host sends ``%``, the blocks and M30 (ISO) on V7: the whole tape in one write, or
    one block per write, each taken by the control before the next is sent."""
    pieces = [encode(text + "\r\n", True) for text in ["%", *blocks, "M30"]]
    with open_port(cnc, "v7") as host:
        for piece in [b"".join(pieces)] if one_write else pieces:
            expected = bytes_in(cnc, "v7") + len(piece)
            host.write(piece)
            until(lambda expected=expected: bytes_in(cnc, "v7") == expected, "the control has taken the bytes")


# -- a block that cannot be stored ends the read-in there (F1) -------------------------------------------
@pytest.mark.manual("§2.6", "Wird vor dem Einlesen eines Programmes eine falsche Baud-Rate oder ein falscher Code "
                    "gewählt, erscheint am Bildschirm: WERTBEREICHES-UEBERLAUF (the transfer stops)")
def test_memory_full_ends_the_read_in_at_that_block_however_the_tape_is_cut(devsim_device: Any) -> None:
    """Spec §3.5.3 (memory full, §4.9 capacity 5 blocks; P01 holds 3): N3 does not fit, so the
    read-in fails there; N1 and N2 stay, the N1 X9 after the failure is not stored and the M30
    after it does not make the transfer ``done`` -- the same whether the host sends the tape
    in one write or one block per write."""
    outcomes = {}
    for one_write in (True, False):
        cnc = devsim_device("poselesta", {"max_blocks_total": 5})
        cnc.set("program.P01", "N1 X1\nN2 X2\nN3 X3")
        await_tape(cnc)
        _send(cnc, ["N1X1", "N2X2", "N3X3", "N1X9"], one_write=one_write)
        outcomes[one_write] = (cnc.read("v7.state"), cnc.read("panel.message"), cnc.read("program.P20"),
                               cnc.read("v7.transfer"))
    assert outcomes[True] == outcomes[False] == ("failed", FULL, "N 1 X 1.000\nN 2 X 2.000", "idle")


@pytest.mark.manual("§2.6.2.3", "Parameterkatalog P 99: vor dem Einlesen wird der gesamte Parameterkatalog "
                    "gelöscht (a value out of range stops the read-in)")
def test_a_catalogue_value_out_of_range_ends_the_read_in_at_that_block(cnc: Any) -> None:
    """Spec §3.9, §4.8 (P30 1 … 99): N30 P500 fails the catalogue read-in; N44 after it is not
    taken and M30 does not make the transfer ``done`` (nor commit the catalogue)."""
    cnc.set("panel.mode", "EXTERNAL_OPERATION")
    cnc.set("panel.program", 99)
    cnc.set("v7.transfer", "input")
    _send(cnc, ["N30P500", "N44P1234", "N70P3"], one_write=True)
    assert cnc.read("v7.state") == "failed"
    assert cnc.read("panel.message") == FULL
    assert cnc.read("param.P44") != 1234


# -- nothing stored, nothing listed (F4) ---------------------------------------------------------------
@pytest.mark.manual("§2.6", "Beim Einlesen eines neuen Programmes wird zuerst das vorgewählte Programm (Pxx) "
                    "gelöscht!")
def test_a_read_in_failing_at_its_first_block_lists_no_program(devsim_device: Any) -> None:
    """Spec §3.5.3: the blocks committed before a failure remain, here none: P20 is not listed,
    as after an empty tape ``% M30``."""
    cnc = devsim_device("poselesta", {"max_blocks_total": 1})
    cnc.set("program.P01", "N1 X1")
    await_tape(cnc)
    _send(cnc, ["N1X1", "N2X2"], one_write=True)
    assert cnc.read("programs") == [1]
    assert cnc.read("program.P20") == ""
    assert cnc.read("v7.state") == "failed" and cnc.read("panel.message") == FULL


# -- the tape's blocks are saved together (F3) -----------------------------------------------------------
@pytest.fixture
def saves(cnc: Any, monkeypatch: pytest.MonkeyPatch) -> Iterator[dict[str, int]]:
    """Counts, in the runtime's thread, the saves of the stored programs to the non-volatile
    memory (``programs``) and the pieces of input a read-in was given (``chunks``)."""
    counts = {"programs": 0, "chunks": 0}
    nvram = cnc.device.nvram
    put, feed = nvram.put_sections, ReadIn.feed  # (every write: put is put_sections of one section)

    def counting_put(sections: dict[str, Any]) -> None:
        counts["programs"] += "programs" in sections
        put(sections)

    def counting_feed(self: ReadIn, data: bytes) -> None:
        counts["chunks"] += 1
        feed(self, data)

    monkeypatch.setattr(nvram, "put_sections", counting_put)
    monkeypatch.setattr(ReadIn, "feed", counting_feed)
    yield counts


@pytest.mark.manual("§2.6", "drei voneinander unabhängige, serielle Schnittstellen (a long read-in does not stall "
                    "the control)")
def test_a_tape_is_saved_once_per_piece_the_host_sends_not_once_per_block(cnc: Any, saves: dict[str, int]) -> None:
    """Spec §3.5.5, §4.9: 200 blocks in one write reach the memory in as many saves as pieces
    of input carried them (a save writes every program: one per block made a read-in
    quadratic); what was counted stored is in the non-volatile memory, and a power cycle keeps it."""
    await_tape(cnc)
    _send(cnc, [f"N{n}X1" for n in range(200)], one_write=True)
    assert cnc.read("v7.state") == "done" and cnc.read("program.P20").count("\n") == 199
    assert saves["chunks"] < 200  # (the tape came in pieces of many blocks)
    assert 1 <= saves["programs"] <= 1 + saves["chunks"]  # (1: the program cleared at the start)
    stored = cnc.runtime.call(lambda: cnc.device.nvram.get("programs"))
    assert len(stored["20"]) == 200
    cnc.power_cycle()
    assert cnc.read("program.P20").count("\n") == 199


def test_a_wipe_in_the_turn_that_read_blocks_in_leaves_them_wiped(cnc: Any) -> None:
    """A power cycle with a wipe handled right after a chunk of a read-in, in the same turn of the
    loop: the chunk's blocks are gone with the rest (a save deferred to the end of the turn wrote
    them back into the wiped memory)."""
    await_tape(cnc)
    tape = encode("%\r\nN1X1\r\nN2X2\r\n", True)
    device = cnc.device

    def read_in_then_wipe() -> None:
        device.port("v7").feed(tape)
        assert device.model.memory.blocks(20)  # stored, the save still to come
        device.model.power_cycle(wipe=True)

    cnc.runtime.call(read_in_then_wipe)
    cnc.advance(5)  # (the boot)
    assert 20 not in cnc.read("programs")
