"""The card's state file (``devsim run gms96 --state-dir``): a file the card wrote loads as it was
written; a hand-edited key or value the card never writes (another script's digits, ``'+3'``,
``'03'``, a fraction, text, a number beyond what its telegram or byte carries) stops the start
with :class:`UnfitMemory` naming the file (manual §2.3.1 s, p, d, G; spec §3.8.6, §3.8.13, §4.8).

The image is made by a real card through its own FT1.2 port (:class:`Gms96Client`)."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import pytest

from devsim.cli import exits
from devsim.runtime import Runtime
from tests.gms96.conftest import start_plant
from tests.gms96.test_motion_reference import send
from tests.support.memory import refused_memory, refused_run, state_image, write_state_image

FLASH_ERASE = 5.0  # manual §2.3.1 p: the card does not answer for 2 to 5 s after p3;100


@pytest.fixture(scope="module")
def saved(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """The image a card wrote: N39 = 7 and N8 = -1000/1000 saved with M, B, S (s85;170), G55 and
    the machine zero entered (G P3 = 1), programs 0 and 3 downloaded, DW2 written (d 1234h;4), a
    PLC program of two frames downloaded."""
    state = tmp_path_factory.mktemp("gms96-saved")
    plant = start_plant([{}], state_dir=state)
    try:
        c = plant.client()
        for command in (("N", 7, 39), ("N", -1000, 8, 0), ("N", 1000, 8, 1), ("M", 30000), ("B", 80), ("S", 300),
                        ("s", 85, 170), ("d", 0x1234, 4), ("G", 55, 1234, 1), ("G", 53, -55, 1)):
            send(c, *command)
        plant.advance(1.0)
        for number, commands in ((0, [("A", 1000), ("A", 0)]), (3, [("A", 500), ("m", 50, 1, 0), ("A", -200)])):
            send(c, "p", 3, 100, number)
            plant.advance(FLASH_ERASE)
            for command in commands:
                send(c, *command)
            send(c, "p", 3, 101)
        plant.advance(1.0)
        send(c, "p", 1, 100)  # a PLC download of two a frames (manual §2.3.1 p, a)
        plant.advance(FLASH_ERASE)
        send(c, "a", 1, 2, 3)
        send(c, "a", 0x10, 0x20)
        send(c, "p", 1, 101)
        plant.advance(1.0)
        plant.runtime.power_cycle("gms96")  # (the static data is saved as the card goes off)
        plant.advance(1.0)
    finally:
        plant.host.close()
        for port in plant._ports:
            port.close()
        plant.runtime.stop()
    return state_image(state, "gms96")


def test_the_image_a_card_saved_loads_as_it_was_saved(tmp_path: Path, saved: dict[str, Any]) -> None:
    write_state_image(tmp_path, "gms96", saved)
    runtime = Runtime(virtual=True, state_dir=tmp_path).start()
    try:
        runtime.add_device("gms96")
        card = runtime.device("gms96").model
        assert runtime.read("gms96", "param.N39") == 7 and runtime.read("gms96", "param.N8") == -1000
        assert (runtime.read("gms96", "param.M"), card.feed.B, card.feed.S) == (30000, 80, 300)
        assert runtime.read("gms96", "programs") == {0: 2, 3: 3}
        assert (card.coordinates.zero_table, card.coordinates.machine_zero) == ({55: 1234}, -55)
        assert card.image.data[4:6] == bytes((0x34, 0x12))
        assert runtime.read("gms96", "plc.image") == "010000020000030000100000200000"
        assert runtime.read("gms96", "plc.frames") == [9, 6]
    finally:
        runtime.stop()


# (section path, key the card writes, keys it never writes: another script's digits, superscripts,
# '_', a blank or a sign, a leading zero (a second entry for the same number), hex, a fraction,
# a number beyond what the card keeps)
KEYS = [
    (("eeprom", "N"), "39", ["٣٩", "³⁹", "３９", "3_9", " 39", "39 ", "+39", "039", "0x27", "39.0", "9" * 25]),
    (("flash", "programs"), "3", ["٣", "²", "3_0", " 3", "+3", "03", "0x3", "3.0", "-3", "100", "-0"]),
    (("offsets", "table"), "55", ["٥٥", "⁵⁵", "5_5", " 55", "+55", "055", "55.0", "53", "70"]),
]


@pytest.mark.parametrize(("where", "key", "edited"),
                         [(where, key, edited) for where, key, keys in KEYS for edited in keys])
def test_a_number_key_the_card_never_writes_refuses_the_memory(tmp_path: Path, saved: dict[str, Any],
                                                               where: tuple[str, str], key: str, edited: str) -> None:
    """(Before: ``int()`` read the key, so N '٣٩' or '+39' was N39, program '03' overwrote
    program 3, '-3' and '1_0' were programs -3 and 10, zero point '+55' was G55.)"""
    image = copy.deepcopy(saved)
    section = image[where[0]][where[1]]
    section[edited] = section.pop(key)
    path = write_state_image(tmp_path, "gms96", image)
    refused = refused_memory(tmp_path, "gms96", match=r"\(ValueError: stored .* (is no number the device writes"
                                                      r"|is none the device stores)\)")
    assert str(refused).startswith(f"{path}: ")


@pytest.mark.parametrize(("where", "value"), [
    (("eeprom", "M"), "٣"), (("eeprom", "M"), "3000"), (("eeprom", "B"), 1.5), (("eeprom", "S"), True),
    (("eeprom", "o"), "0"), (("eeprom", "o"), 2),
    (("offsets", "machine_zero"), "٣"), (("offsets", "machine_zero"), 2**23), (("offsets", "machine_zero"), 1.0),
    (("static", "mb18"), 128), (("static", "mb18"), "5"),
])
def test_a_stored_value_the_card_never_writes_refuses_the_memory(tmp_path: Path, saved: dict[str, Any],
                                                                 where: tuple[str, str], value: Any) -> None:
    """(Before: ``int()`` took "٣", "3000", 1.5 and true as speeds and offsets, and ``& 0xFF``
    made a tool number 128 another one; ``bool("0")`` switched the override on.)"""
    image = copy.deepcopy(saved)
    image.setdefault(where[0], {})[where[1]] = value
    write_state_image(tmp_path, "gms96", image)
    refused_memory(tmp_path, "gms96", match=r"\(ValueError: stored .* is none the device stores\)")


FALSY = [{}, [], None, 0, "", False]


def _entry(section: str, key: str, value: Any) -> Any:
    def change(image: dict[str, Any]) -> None:
        image[section][key] = value
    return change


def _section(section: str, value: Any) -> Any:
    return lambda image: image.__setitem__(section, value)


def _without(section: str, key: str) -> Any:
    return lambda image: image[section].pop(key)


# what each save writes: eeprom (s85;170) M, B, S, o, every N and both N8; static all 160 data bytes
# and MB18; offsets the table (maybe empty) and the machine zero; flash the programs (maybe none),
# the PLC image (null without one) and its frames (an older devsim wrote no frames)
SECTION_EDITS: dict[str, Any] = {
    **{f"{section}-{value!r}": _section(section, value)
       for section in ("eeprom", "static", "offsets", "flash") for value in FALSY},
    **{f"eeprom-N-{value!r}": _entry("eeprom", "N", value) for value in FALSY},
    **{f"eeprom-N8-{value!r}": _entry("eeprom", "N8", value) for value in FALSY},
    **{f"static-data-{value!r}": _entry("static", "data", value) for value in FALSY},
    "static-data-159-bytes": lambda image: image["static"]["data"].pop(),
    **{f"offsets-table-{value!r}": _entry("offsets", "table", value) for value in FALSY if value != {}},
    **{f"flash-programs-{value!r}": _entry("flash", "programs", value) for value in FALSY if value != {}},
    "flash-plc-empty": lambda image: image["flash"].update(plc="", plc_frames=[]),
    "flash-plc-frames-null": _entry("flash", "plc_frames", None),
    **{f"{section}-without-{key}": _without(section, key) for section, keys in (
        ("eeprom", "MBSoN"), ("static", ("data", "mb18")), ("offsets", ("table", "machine_zero")),
        ("flash", ("programs", "plc"))) for key in ([*keys, "N8"] if section == "eeprom" else keys)},
    **{f"{section}-extra-entry": _entry(section, "x", 0) for section in ("eeprom", "static", "offsets", "flash")},
}


@pytest.mark.parametrize("edit", list(SECTION_EDITS))
def test_a_section_the_card_never_writes_refuses_the_memory(tmp_path: Path, saved: dict[str, Any], edit: str) -> None:
    """(Before: an empty or falsy section or entry, ``{}``, ``[]``, null, ``0``, ``""``, read as none
    stored, so a damaged file started the card on factory data without a word; a missing entry
    took a default and an extra one was ignored.)"""
    image = copy.deepcopy(saved)
    SECTION_EDITS[edit](image)
    path = write_state_image(tmp_path, "gms96", image)
    text = path.read_text("utf-8")
    refused_memory(tmp_path, "gms96", match="this memory image does not fit the kind 'gms96'")
    assert path.read_text("utf-8") == text


def test_a_memory_no_save_reached_starts_on_the_factory_data(tmp_path: Path, saved: dict[str, Any]) -> None:
    """No section at all (a wiped memory, a card that never saved) is what the card writes: defaults."""
    write_state_image(tmp_path, "gms96", {"devsim-kind": saved["devsim-kind"]})
    runtime = Runtime(virtual=True, state_dir=tmp_path).start()
    try:
        runtime.add_device("gms96")
        card = runtime.device("gms96").model
        assert runtime.read("gms96", "programs") == {} and runtime.read("gms96", "plc.frames") == []
        assert (card.coordinates.zero_table, card.coordinates.machine_zero, card.image.markers[18]) == ({}, 0, 0)
    finally:
        runtime.stop()


@pytest.mark.parametrize(("table", "data"), [({"55": "٣"}, None), ({"55": 2**23}, None), ({"55": -2**23 - 1}, None),
                                             ({}, [1, 2, 256]), ({}, [-1]), ({}, ["٣"]), ({}, [0] * 161)])
def test_a_stored_offset_or_data_byte_the_card_never_writes_refuses_the_memory(
        tmp_path: Path, saved: dict[str, Any], table: dict[str, Any], data: Any) -> None:
    image = copy.deepcopy(saved)
    image["offsets"]["table"] = table
    if data is not None:
        image["static"] = {"data": data, "mb18": 0}
    write_state_image(tmp_path, "gms96", image)
    refused_memory(tmp_path, "gms96", match=r"\(ValueError: stored .* (is none the device stores|is no 160 bytes)\)")


def test_a_stored_speed_beyond_its_range_is_clamped_as_a_write_is(tmp_path: Path, saved: dict[str, Any]) -> None:
    """What ``M``, ``B``, ``S`` store is clamped to their ranges (spec §3.8.12): so is a hand-edited
    EEPROM (before: M 10**30 loaded as it was)."""
    image = copy.deepcopy(saved)
    image["eeprom"].update(M=10**30, B=-5, S=10**6)
    write_state_image(tmp_path, "gms96", image)
    runtime = Runtime(virtual=True, state_dir=tmp_path).start()
    try:
        runtime.add_device("gms96")
        feed = runtime.device("gms96").model.feed
        assert (feed.M, feed.B, feed.S) == (2_000_000, 1, 5_000)
    finally:
        runtime.stop()


def test_devsim_run_on_a_state_file_with_another_scripts_digits_stops_naming_it(
        tmp_path: Path, saved: dict[str, Any]) -> None:
    """A real ``devsim run gms96 --pty --state-dir``: N '٣٩' stops the start in one line naming
    the file, no traceback, the file left as it is (before: the card started with N39 = 50)."""
    image = copy.deepcopy(saved)
    image["eeprom"]["N"]["٣٩"] = 50
    path = write_state_image(tmp_path, "gms96", image)
    text = path.read_text("utf-8")
    code, err = refused_run("gms96", tmp_path)
    assert code == exits.SYSTEM
    assert err == (f"Error: cannot create the devices: {path}: this memory image does not fit the kind 'gms96'"
                   " (ValueError: stored N parameter '٣٩' is no number the device writes); fix or delete the file\n")
    assert path.read_text("utf-8") == text


@pytest.mark.parametrize("row", [["A", 2**23, 0, 0, 1], ["A", -2**23 - 1, 0, 0, 1], ["A", 10**30, 0, 0, 1],
                                 ["m", 50, 1, 2**31, 3], ["A", 1000, 0, 0, 4], ["A", 1000, 0, 0, -1],
                                 ["A", 1000, 5, 0, 1]])
def test_a_stored_program_row_no_telegram_carries_refuses_the_memory(tmp_path: Path, saved: dict[str, Any],
                                                                     row: list[Any]) -> None:
    """(Mutating the card's image: P1 = 10**30, a count of 4 or -1 loaded, and program.3 served
    'A1000000000000000000000000000000'; a telegram carries three 24-bit parameters, spec
    Appendix B, and the ones not sent are 0.)"""
    image = copy.deepcopy(saved)
    image["flash"]["programs"]["3"][1] = row
    write_state_image(tmp_path, "gms96", image)
    refused_memory(tmp_path, "gms96", match=r"\(ValueError: stored program row .* is no command a 24-bit telegram")


@pytest.mark.parametrize(("plc", "frames"), [
    (True, [9, 6]), (5, [9, 6]), ([1], [9, 6]), ({}, [9, 6]), ("x", [9, 6]), ("٣٣", [1]), ("0A", [1]), ("0a0", [1]),
    ("0a", [9, 6]), ("010000020000030000100000200000", [9, 7]), ("010000020000030000100000200000", "15"),
    ("010000020000030000100000200000", [9.0, 6]), ("010000020000030000100000200000", [-1, 16]), (None, [9, 6]),
])
def test_a_stored_plc_image_no_download_makes_refuses_the_memory(tmp_path: Path, saved: dict[str, Any],
                                                                 plc: Any, frames: Any) -> None:
    """(Mutating the card's image: an image of true, 5, a list or an object loaded and every read of
    plc, plc.running ... and state() failed with TypeError; "x", "0a" with frames of 15 bytes, or
    frames that are no lengths loaded and were served as the downloaded program.)"""
    image = copy.deepcopy(saved)
    image["flash"].update(plc=plc, plc_frames=frames)
    write_state_image(tmp_path, "gms96", image)
    refused_memory(tmp_path, "gms96", match=r"\(ValueError: stored PLC (image|frame)")


def test_a_plc_image_an_older_devsim_stored_without_its_frames_loads_as_one_frame(
        tmp_path: Path, saved: dict[str, Any]) -> None:
    image = copy.deepcopy(saved)
    del image["flash"]["plc_frames"]
    write_state_image(tmp_path, "gms96", image)
    runtime = Runtime(virtual=True, state_dir=tmp_path).start()
    try:
        runtime.add_device("gms96")
        assert runtime.read("gms96", "plc.frames") == [15]
        assert runtime.state("gms96")["plc"]["image_bytes"] == 15
    finally:
        runtime.stop()


@pytest.mark.parametrize("config", [{"max_programs": 3}, {"max_total_commands": 4}, {"plc": {"flash_bytes": 14}}])
def test_a_flash_beyond_the_configured_memory_refuses_the_memory(tmp_path: Path, saved: dict[str, Any],
                                                                config: dict[str, Any]) -> None:
    """[SIM-CHOICE] The card's FLASH (programs 0 and 3, 5 commands, a PLC image of 15 bytes) on a card
    configured to hold less: refused at the start (before: program 3 loaded on a card keeping programs
    0 … 2, more commands or PLC bytes than any download could store there)."""
    path = write_state_image(tmp_path, "gms96", saved)
    text = path.read_text("utf-8")
    refused_memory(tmp_path, "gms96", config=config, match=r"\(ValueError: the stored FLASH holds more than the configured")
    assert path.read_text("utf-8") == text


def test_a_flash_filling_the_configured_memory_loads(tmp_path: Path, saved: dict[str, Any]) -> None:
    write_state_image(tmp_path, "gms96", saved)
    runtime = Runtime(virtual=True, state_dir=tmp_path).start()
    try:
        runtime.add_device("gms96", None, {"max_programs": 4, "max_total_commands": 5, "plc": {"flash_bytes": 15}})
        assert runtime.read("gms96", "programs") == {0: 2, 3: 3} and runtime.read("gms96", "plc.frames") == [9, 6]
    finally:
        runtime.stop()
