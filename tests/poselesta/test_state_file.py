"""The control's state file (``devsim run poselesta --state-dir``): a file the control wrote loads
as it was written; a hand-edited number key the control never writes (another script's digits,
``'+41'``, ``'041'``: a second entry for a number already stored) or a block number twice stops the
start with :class:`UnfitMemory` naming the file (manual §2.3.14, §2.3.21, §2.6.2.3, §2.6.3; spec §4.8).

The image is made by a real control: programs entered, a tool and a parameter set, a program
protected, through the control API."""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

import pytest

from devsim.cli import exits
from devsim.runtime import Runtime
from tests.support.memory import killed_at_write, refused_memory, refused_run, state_image, write_state_image


@pytest.fixture(scope="module")
def saved(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    state = tmp_path_factory.mktemp("poselesta-saved")
    runtime = Runtime(virtual=True, state_dir=state).start()
    try:
        runtime.add_device("poselesta")
        runtime.advance(3.0)
        runtime.set("poselesta", "program.P20", "N1 G01 X10 F500\nN2 X20 Y5\nN3 M02")
        runtime.set("poselesta", "program.P03", "N5 X1\nN10 X2")
        runtime.set("poselesta", "tool.T05", {"radius": 4.0, "length": 120.5})
        runtime.set("poselesta", "param.P41", 3)
        runtime.set("poselesta", "panel.protect", 3)
    finally:
        runtime.stop()
    return state_image(state, "poselesta")


def test_the_image_a_control_saved_loads_as_it_was_saved(tmp_path: Path, saved: dict[str, Any]) -> None:
    write_state_image(tmp_path, "poselesta", saved)
    runtime = Runtime(virtual=True, state_dir=tmp_path).start()
    try:
        runtime.add_device("poselesta")
        assert runtime.read("poselesta", "programs") == [3, 20]
        assert runtime.read("poselesta", "program.P03") == "N 5 X 1.000\nN 10 X 2.000"
        assert runtime.read("poselesta", "tool.T05") == {"radius": 4.0, "length": 120.5}
        assert runtime.read("poselesta", "param.P41") == 3.0
        assert runtime.read("poselesta", "protected") == [3]
    finally:
        runtime.stop()


# (section, key the control writes, keys it never writes: another script's digits, superscripts,
# full-width digits, '_', a blank or a sign, a leading zero (a second entry for the same number),
# hex, a fraction, more digits than any number has)
KEYS = [
    ("params", "41", ["٤١", "⁴¹", "４１", "4_1", " 41", "+41", "041", "0x29", "41.0", "9" * 20]),
    ("programs", "3", ["٣", "³", "３", "0_3", " 3", "+3", "03", "0x3", "3.0", "-0"]),
    ("tools", "5", ["٥", "⁵", "0_5", " 5", "+5", "05", "5.0"]),
]


@pytest.mark.parametrize(("section", "key", "edited"),
                         [(section, key, edited) for section, key, keys in KEYS for edited in keys])
def test_a_number_key_the_control_never_writes_refuses_the_memory(tmp_path: Path, saved: dict[str, Any],
                                                                  section: str, key: str, edited: str) -> None:
    """(Before: ``int()`` read a parameter key, so '٤١', '４１', '+41', ' 41', '041' or '4_1' was
    P41; a program or tool key '03' or '05' was P03 or T05, replacing the stored one.)"""
    image = copy.deepcopy(saved)
    image[section][edited] = image[section].pop(key)
    path = write_state_image(tmp_path, "poselesta", image)
    refused = refused_memory(tmp_path, "poselesta",
                             match=r"\(ValueError: stored (parameter|program|tool) .* is no number the device writes\)")
    assert str(refused).startswith(f"{path}: ")


def test_a_block_number_twice_in_a_program_refuses_the_memory(tmp_path: Path, saved: dict[str, Any]) -> None:
    """A read-in or program entry replaces a block of the same number, so a program never holds
    one twice (before: the second N5 of a hand-edited P03 silently replaced the first)."""
    image = copy.deepcopy(saved)
    image["programs"]["3"].append({"N": 5, "skip": False, "words": [["X", 9000]]})
    write_state_image(tmp_path, "poselesta", image)
    refused_memory(tmp_path, "poselesta", match=r"\(ValueError: stored program P03 holds a block number twice\)")


# what each section's save writes: an object of every parameter; objects of programs and tools and
# lists of protected and inch programs, any of them maybe empty; the tape as text
NEVER_WRITTEN = [("params", value) for value in (None, {}, [], 0, "", False)] + [
    (section, value) for section in ("programs", "tools") for value in (None, [], 0, "", False)] + [
    (section, value) for section in ("protected", "inch_programs") for value in (None, {}, 0, "", False)]


@pytest.mark.parametrize(("section", "value"), NEVER_WRITTEN)
def test_a_section_the_control_never_writes_refuses_the_memory(tmp_path: Path, saved: dict[str, Any],
                                                               section: str, value: Any) -> None:
    """(Before: ``or {}`` / ``or []`` read null, 0, "" and the other kind of empty container as an
    empty memory, and null or {} parameters as nothing saved or no parameter: the programs, tools,
    protection or parameters gone without a word.)"""
    image = copy.deepcopy(saved)
    image[section] = value
    path = write_state_image(tmp_path, "poselesta", image)
    text = path.read_text("utf-8")
    refused_memory(tmp_path, "poselesta", match="this memory image does not fit the kind 'poselesta'")
    assert path.read_text("utf-8") == text


def test_programs_beyond_the_configured_memory_refuse_the_memory(tmp_path: Path, saved: dict[str, Any]) -> None:
    """[SIM-CHOICE] The control's 5 stored blocks (P20: 3, P03: 2) on a control configured with
    ``max_blocks_total`` 4 are refused at the start (before: they loaded, more than any read-in or
    entry stores there); with 5 they load."""
    path = write_state_image(tmp_path, "poselesta", saved)
    text = path.read_text("utf-8")
    refused_memory(tmp_path, "poselesta", config={"max_blocks_total": 4},
                   match=r"\(ValueError: the stored programs hold 5 blocks, more than the configured max_blocks_total 4\)")
    assert path.read_text("utf-8") == text
    runtime = Runtime(virtual=True, state_dir=tmp_path).start()
    try:
        runtime.add_device("poselesta", None, {"max_blocks_total": 5})
        assert runtime.read("poselesta", "programs") == [3, 20]
    finally:
        runtime.stop()


def test_devsim_run_on_a_state_file_with_another_scripts_digits_stops_naming_it(
        tmp_path: Path, saved: dict[str, Any]) -> None:
    """A real ``devsim run poselesta --pty --state-dir``: parameter '٤١' stops the start in one
    line naming the file, no traceback, the file left as it is (before: the control started
    with P41 = 7)."""
    image = copy.deepcopy(saved)
    image["params"]["٤١"] = 7
    path = write_state_image(tmp_path, "poselesta", image)
    text = path.read_text("utf-8")
    code, err = refused_run("poselesta", tmp_path)
    assert code == exits.SYSTEM
    assert err == (f"Error: cannot create the devices: {path}: this memory image does not fit the kind 'poselesta'"
                   " (ValueError: stored parameter '٤١' is no number the device writes); fix or delete the file\n")
    assert path.read_text("utf-8") == text


@pytest.mark.parametrize(("number", "value"), [("68", 7), ("68", 2.5), ("30", 1e30), ("30", -5), ("72", 100)])
def test_a_stored_parameter_value_the_control_never_takes_refuses_the_memory(
        tmp_path: Path, saved: dict[str, Any], number: str, value: float) -> None:
    """(Before: P68 = 7, no baud rate code, or P30 = 1e30 loaded and were served; an entry, a
    catalogue block or the config refuses them, check_parameter.)"""
    image = copy.deepcopy(saved)
    image["params"][number] = value
    write_state_image(tmp_path, "poselesta", image)
    refused_memory(tmp_path, "poselesta", match=rf"\(ValueError: P{number}: .* is not a whole number in")


def test_a_stored_parameter_a_catalogue_read_in_left_at_0_loads(tmp_path: Path, saved: dict[str, Any]) -> None:
    """A catalogue read-in first sets every parameter 0 (manual §2.6.2.3); one that never reached
    its M30 leaves P30 at 0, below its range, and the control keeps it so."""
    image = copy.deepcopy(saved)
    image["params"]["30"] = 0
    write_state_image(tmp_path, "poselesta", image)
    runtime = Runtime(virtual=True, state_dir=tmp_path).start()
    try:
        runtime.add_device("poselesta")
        assert runtime.read("poselesta", "param.P30") == 0.0
    finally:
        runtime.stop()


# -- the cassette recorder's tape (config v6_peer: cassette, manual §2.6.2.2) ---------------------------
CASSETTE = {"v6_peer": "cassette"}


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """The image a control with a cassette recorder on V6 wrote: P20 recorded with T2 (ISO)."""
    state = tmp_path_factory.mktemp("poselesta-cassette")
    runtime = Runtime(virtual=True, state_dir=state).start()
    try:
        runtime.add_device("poselesta", None, CASSETTE)
        runtime.advance(3.0)
        runtime.set("poselesta", "program.P20", "N1 X10\nN2 Y-2.5 M02")
        runtime.set("poselesta", "panel.mode", "EXTERNAL_MEDIUM")
        runtime.set("poselesta", "panel.program", 20)
        runtime.set("poselesta", "v6.transfer", "cassette_out")
        runtime.advance(20.0)  # the 13 s leader, then the program
        assert runtime.read("poselesta", "v6.state") == "done"
    finally:
        runtime.stop()
    return state_image(state, "poselesta")


def test_the_tape_a_cassette_recorded_plays_back_after_a_restart(tmp_path: Path, recorded: dict[str, Any]) -> None:
    assert recorded["cassette"].startswith("a58d0a")  # ISO "%" CR LF
    write_state_image(tmp_path, "poselesta", recorded)
    runtime = Runtime(virtual=True, state_dir=tmp_path).start()
    try:
        runtime.add_device("poselesta", None, CASSETTE)
        runtime.advance(3.0)
        runtime.set("poselesta", "panel.mode", "EXTERNAL_MEDIUM")
        runtime.set("poselesta", "panel.program", 21)
        runtime.set("poselesta", "v6.transfer", "cassette_in")
        runtime.advance(20.0)
        assert runtime.read("poselesta", "v6.state") == "done"
        assert runtime.read("poselesta", "program.P21") == "N 1 X 10.000\nN 2 Y- 2.500 M 02"
    finally:
        runtime.stop()


TAPES = {  # what the recorder never keeps (bytes.hex(), "" when ejected)
    "number": 5, "zero": 0, "false": False, "null": None, "list": [], "object": {}, "huge": 10**30,
    "capitals": str.upper, "blanks": lambda t: " ".join(t[i:i + 2] for i in range(0, len(t), 2)),
    "newline": lambda t: t[:4] + "\n" + t[4:], "odd-length": lambda t: t[:-1], "not-hex": lambda t: "zz" + t,
    "arabic-indic-digits": lambda t: "\u0664\u0661" + t, "fullwidth-digits": lambda t: "\uff14\uff11" + t,
}


@pytest.mark.parametrize("edit", list(TAPES))
def test_a_tape_the_recorder_never_keeps_refuses_the_memory(tmp_path: Path, recorded: dict[str, Any],
                                                           edit: str) -> None:
    """(Fuzzed through a real start: a number, null, [] or {} loaded as an empty tape, the
    recording gone without a word; capitals, blanks and newlines were read by ``fromhex``.)"""
    image = copy.deepcopy(recorded)
    change = TAPES[edit]
    image["cassette"] = change(image["cassette"]) if callable(change) else change
    path = write_state_image(tmp_path, "poselesta", image)
    text = path.read_text("utf-8")
    refused_memory(tmp_path, "poselesta", match=r"\(ValueError: the stored cassette .* is no tape the recorder keeps",
                   config=CASSETTE)
    assert path.read_text("utf-8") == text


@pytest.mark.parametrize("at", [1, 2])
def test_a_program_typed_in_inch_and_killed_while_saved_keeps_its_inch_mark(tmp_path: Path, at: int) -> None:
    """P20 entered in inch (V22/2 H) on a control killed as it writes the file for the ``at``-th
    time: the file holds the program with its inch mark, or neither.  (Before: the programs and
    the inch mark were two writes, so a kill between them left P20's inch numbers marked as mm,
    read with other decimals after the restart.)"""
    from devsim.core.clock import VirtualClock
    from devsim.core.nvram import NonVolatileMemory
    from devsim.devices.poselesta.model import PoselestaCnc

    nvram = NonVolatileMemory.for_device(tmp_path, "poselesta", "poselesta")
    try:
        cnc = PoselestaCnc(clock=VirtualClock(), config={}, nvram=nvram)
        cnc.signals.set("inch", True)
        with killed_at_write(nvram, at) as writes:
            cnc.memory.set_program_text(20, "N1 X1.00001")
    finally:
        nvram.close()
    path = tmp_path / "poselesta.nvram.json"
    image = json.loads(path.read_text("utf-8")) if path.exists() else {}
    assert ("20" in image.get("programs", {})) == (20 in image.get("inch_programs", []))
    assert len(writes) == at or image["inch_programs"] == [20]  # (no kill: the save finished)


@pytest.mark.parametrize("at", [1, 2])
def test_a_block_entered_in_inch_and_killed_while_saved_keeps_its_inch_mark(tmp_path: Path, at: int) -> None:
    """One block of a new program P20 entered (``panel.edit_block``) in inch (V22/2 H) on a control
    killed as it writes the file for the ``at``-th time: the file holds the block with P20's inch
    mark, or neither.  (Before: the inch mark was written first, the block only at the next
    read-in chunk or at the end, so a kill after the entry left the mark of a program never
    stored and lost the block.)"""
    from devsim.core.clock import VirtualClock
    from devsim.core.nvram import NonVolatileMemory
    from devsim.devices.poselesta.model import PoselestaCnc

    nvram = NonVolatileMemory.for_device(tmp_path, "poselesta", "poselesta")
    try:
        cnc = PoselestaCnc(clock=VirtualClock(), config={}, nvram=nvram)
        cnc.signals.set("inch", True)
        with killed_at_write(nvram, at) as writes:
            cnc.memory.edit_block("20: N5 X1.00001")  # (what panel.edit_block puts)
    finally:
        nvram.close()
    path = tmp_path / "poselesta.nvram.json"
    image = json.loads(path.read_text("utf-8")) if path.exists() else {}
    assert ("20" in image.get("programs", {})) == (20 in image.get("inch_programs", []))
    assert len(writes) == at or image["inch_programs"] == [20]  # (no kill: the entry is saved)
