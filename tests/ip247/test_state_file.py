"""The module's battery RAM in its state file (``devsim run ip247 --state-dir``): a file the module
wrote loads as it was written; a hand-edited key or value the module never writes (an axis key
as ``'01'``, ``'+1'`` or another script's digits, an axis the module has not, a section that is
no object of axes, an empty SYS-ID or program memory) stops the start with :class:`UnfitMemory`
naming the file (spec ip247.md §4.14; the kit's ``numbered`` as the other kinds read theirs).

The image is made by a real module through its PG port (AS511, :class:`tests.ip247.helpers.Module`)."""

from __future__ import annotations

import copy
import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from devsim.pytest_plugin import DeviceFactory
from devsim.runtime import Runtime
from tests.ip247.helpers import FORWARD, Module
from tests.support.memory import killed_at_write, refused_memory, state_image, write_state_image

PROGRAM = "%  9\nN1 X1 F100\nN2 M02\n"


@pytest.fixture(scope="module")
def saved(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """The battery RAM a module wrote: COM247's MD on axes 1 and 2 (BA20), program 9 (BA22), a
    BA15 offset of 2000 on axis 1, SYS-ID module 11 slot 1 from the configuration."""
    state = tmp_path_factory.mktemp("ip247-saved")
    factory = DeviceFactory()
    try:
        mod = Module(factory("ip247", {"sys_id": {"module": 11, "slot": 1}}, state_dir=state))
        try:
            mod.ready()
            assert mod.load_md(2)[8] == 0
            assert mod.store(9, PROGRAM)[8] == 0
            mod.operate(1, 15, FORWARD, dd=2_000)
            assert mod.m.units[0].coords.to_ba15 == 2_000
        finally:
            mod.port.close()
    finally:
        factory.close()
    return state_image(state, "ip247")


def test_the_image_a_module_saved_loads_as_it_was_saved(tmp_path: Path, saved: dict[str, Any]) -> None:
    assert sorted(saved["md"]) == ["1", "2"] and sorted(saved["offsets"]) == ["1", "2", "3"]
    write_state_image(tmp_path, "ip247", saved)
    runtime = Runtime(virtual=True, state_dir=tmp_path).start()
    try:
        m = runtime.add_device("ip247").model
        assert m.channel.sys_id == (11, 1, 0)
        assert [u.md_valid for u in m.units] == [True, True, False]
        assert [u.coords.to_ba15 for u in m.units] == [2_000, 0, 0]
        assert m.programs.store.directory() == [(9, 5 + (len(PROGRAM) + 1) // 2)]
    finally:
        runtime.stop()


def test_battery_ram_without_offsets_loads_them_as_zero(tmp_path: Path, saved: dict[str, Any]) -> None:
    """No ``offsets`` section at all is battery RAM no save has written them to (a wiped one, or an
    older devsim killed between the first save's writes of ``md`` and ``offsets``): all zero."""
    image = copy.deepcopy(saved)
    del image["offsets"]
    write_state_image(tmp_path, "ip247", image)
    runtime = Runtime(virtual=True, state_dir=tmp_path).start()
    try:
        m = runtime.add_device("ip247").model
        assert [u.md_valid for u in m.units] == [True, True, False]
        assert [(u.coords.zo_mode, u.coords.to_ba15, u.coords.to_prog) for u in m.units] == [(0, 0, 0)] * 3
    finally:
        runtime.stop()


def _rekey(section: str, old: str, new: str) -> Callable[[dict[str, Any]], None]:
    def change(image: dict[str, Any]) -> None:
        image[section][new] = image[section].pop(old)
    return change


def _set(section: str, value: object) -> Callable[[dict[str, Any]], None]:
    def change(image: dict[str, Any]) -> None:
        image[section] = value
    return change


def _without_md(section: str, value: object) -> Callable[[dict[str, Any]], None]:
    def change(image: dict[str, Any]) -> None:
        del image["md"]
        image[section] = value
    return change


def _offsets_of_axis_1(value: object) -> Callable[[dict[str, Any]], None]:
    def change(image: dict[str, Any]) -> None:
        image["offsets"]["1"] = value
    return change


EDITS = {
    # an axis key save() never writes (str(n)); before, the axis started without its MD or
    # offsets (int() reads '٣' and '+1', dict.get found none of them), not a word said
    "md-key-01": _rekey("md", "1", "01"),
    "md-key-plus": _rekey("md", "1", "+1"),
    "md-key-arabic-indic": _rekey("md", "1", "\u0661"),
    "md-key-space": _rekey("md", "1", " 1"),
    "md-key-axis-4": _rekey("md", "2", "4"),
    "md-key-axis-0": _rekey("md", "2", "0"),
    "offsets-key-01": _rekey("offsets", "1", "01"),
    "offsets-key-plus": _rekey("offsets", "1", "+1"),
    "offsets-key-devanagari": _rekey("offsets", "1", "\u0967"),
    "offsets-key-fraction": _rekey("offsets", "1", "1.0"),
    "offsets-key-axis-minus-1": _rekey("offsets", "3", "-1"),
    # a section that is no object of axes; before, an empty one read as no data
    "md-list": _set("md", []),
    "md-zero": _set("md", 0),
    "md-null": _set("md", None),
    "offsets-list": _set("offsets", []),
    "offsets-false": _set("offsets", False),
    # an axis missing from the offsets: every save() writes all three axes' (before: it loaded as 0)
    "offsets-without-axis-1": lambda image: image["offsets"].pop("1"),
    "offsets-without-axis-3": lambda image: image["offsets"].pop("3"),
    "offsets-empty": _set("offsets", {}),
    "offsets-of-axis-as-object": _offsets_of_axis_1({"a": 0, "b": 2_000, "c": 0}),  # (refused before too)
    "offsets-of-axis-as-text": _offsets_of_axis_1("abc"),  # (refused before too)
    # an empty SYS-ID or program memory: the module always writes three bytes and both entries
    # (the SYS-ID without the MD, whose module number it would no longer match)
    "sys-id-empty": _without_md("sys_id", []),
    "sys-id-zero": _without_md("sys_id", 0),
    "sys-id-null": _without_md("sys_id", None),
    "programs-null": _set("programs", None),
    "programs-empty-object": _set("programs", {}),
    "programs-empty-list": _set("programs", []),
    "programs-extra-entry": lambda image: image["programs"].__setitem__("gaps2", 0),
}


@pytest.mark.parametrize("edit", list(EDITS))
def test_a_key_or_value_the_module_never_writes_refuses_the_memory(
        tmp_path: Path, saved: dict[str, Any], edit: str) -> None:
    image = copy.deepcopy(saved)
    EDITS[edit](image)
    text = write_state_image(tmp_path, "ip247", image).read_text("utf-8")
    refused_memory(tmp_path, "ip247", match="this memory image does not fit the kind 'ip247'")
    assert (tmp_path / "ip247.nvram.json").read_text("utf-8") == text


@pytest.mark.parametrize("at", [1, 2, 3, 4])
def test_a_save_killed_at_any_of_its_writes_leaves_all_of_battery_ram_or_none(tmp_path: Path, at: int) -> None:
    """A module saving its battery RAM (an offset on axis 1, the SYS-ID from the configuration) is
    killed as it writes the file for the ``at``-th time: the file holds every section a save
    writes or none of them.  (Before: save() wrote md, offsets, programs and sys_id one write each,
    so a kill after the first left md alone, which loads with the offsets at 0 and the
    configuration's SYS-ID, not a word said.)"""
    from devsim.core.clock import VirtualClock
    from devsim.core.nvram import NonVolatileMemory
    from devsim.devices.ip247.module import Ip247Module

    nvram = NonVolatileMemory.for_device(tmp_path, "ip247", "ip247")
    try:
        module = Ip247Module(clock=VirtualClock(), config={"sys_id": {"module": 11}}, nvram=nvram)
        module.units[0].coords.to_ba15 = 2_000
        with killed_at_write(nvram, at):
            module.save()
    finally:
        nvram.close()
    path = tmp_path / "ip247.nvram.json"
    sections = set(json.loads(path.read_text("utf-8"))) - {"devsim-kind"} if path.exists() else set()
    assert sections in (set(), {"md", "offsets", "programs", "sys_id"})
