"""Non-volatile memory: one owner per device memory, nothing non-finite in or out, safe names."""

from __future__ import annotations

import json
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from devsim.core.nvram import (
    MemoryInUse,
    NonVolatileMemory,
    PoisonedMemory,
    check_name,
    numbered,
    stored_key,
    stored_whole,
)
from tests.support.memory import refused_memory


def test_a_second_owner_is_refused_and_the_first_keeps_its_files(tmp_path: Path) -> None:
    first = NonVolatileMemory.for_device(tmp_path, "drive")
    first.put("params", {"P51": 1})
    stale = tmp_path / "drive.nvram.json.abc.tmp"
    stale.write_text("{}")  # as if the first one were writing right now
    with pytest.raises(MemoryInUse, match=rf"'drive' is in use by another simulator \(pid {os.getpid()}\)"):
        NonVolatileMemory.for_device(tmp_path, "drive")
    assert stale.exists()  # the refused one deleted nothing
    first.close()
    second = NonVolatileMemory.for_device(tmp_path, "drive")  # free again once released
    assert second.get("params") == {"P51": 1}
    assert not stale.exists()  # the new owner cleans up what a killed writer left
    second.close()


def test_the_lock_holds_across_processes(tmp_path: Path) -> None:
    mine = NonVolatileMemory.for_device(tmp_path, "card")
    code = (
        "import sys\n"
        "from devsim.core.nvram import MemoryInUse, NonVolatileMemory\n"
        "try:\n"
        f"    NonVolatileMemory.for_device({str(tmp_path)!r}, 'card')\n"
        "except MemoryInUse as exc:\n"
        "    print(exc); sys.exit(3)\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert done.returncode == 3 and "in use by another simulator" in done.stdout
    mine.close()
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stdout + done.stderr


def test_devsim_run_on_a_held_memory_says_so_as_devsim_up_does(tmp_path: Path) -> None:
    """`devsim run` on a state dir another simulator holds: one line in the memory's own words and
    status 6, as `devsim up` says it (it said `cannot create the devices: MemoryInUse: ...`)."""
    from tests.support.process import devsim_env

    held = NonVolatileMemory.for_device(tmp_path, "sers")
    try:
        done = subprocess.run([sys.executable, "-m", "devsim", "run", "sers", "--no-control", "--state-dir",
                               str(tmp_path)], capture_output=True, text=True, timeout=60, env=devsim_env(),
                              stdin=subprocess.DEVNULL)
    finally:
        held.close()
    assert done.returncode == 6
    assert done.stderr == (f"Error: cannot create the devices: {tmp_path}: the memory of 'sers' is in use by another"
                           f" simulator (pid {os.getpid()}); give each simulator its own --state-dir\n")


@pytest.mark.parametrize("token", ["NaN", "Infinity", "-Infinity", "1e999", "-2.5E+400"])
def test_a_poisoned_image_is_refused_at_load(tmp_path: Path, token: str) -> None:
    """(``1e999``, a number beyond the floats, was read as infinity and loaded: fuzzed.)"""
    (tmp_path / "drive.nvram.json").write_text(f'{{"params": {{"V": {token}}}}}')
    with pytest.raises(PoisonedMemory, match=rf"non-finite number \({re.escape(token)}\); refusing to load"):
        NonVolatileMemory.for_device(tmp_path, "drive")
    (tmp_path / "drive.nvram.json").unlink()
    NonVolatileMemory.for_device(tmp_path, "drive").close()  # the refusal released the lock


def test_nothing_non_finite_is_written(tmp_path: Path) -> None:
    memory = NonVolatileMemory.for_device(tmp_path, "drive")
    memory.put("params", {"V": 1.5})
    with pytest.raises(PoisonedMemory):
        memory.put("params", {"V": math.nan})
    with pytest.raises(PoisonedMemory):
        memory.put("program", [math.inf])
    with pytest.raises(PoisonedMemory):  # (a lone surrogate: UnicodeEncodeError, and every later save failed)
        memory.put("program", ["\udcff"])
    # the refused values are not kept either: later saves go on, and the sections hold what they held
    assert memory.get("params") == {"V": 1.5} and memory.sections() == ["params"]
    memory.put("speed", 7)
    memory.close()
    assert json.loads((tmp_path / "drive.nvram.json").read_text()) == {"params": {"V": 1.5}, "speed": 7}


@pytest.mark.parametrize("text", ["{not json", "[" * 100_000, "", "[]", "42", "null", '"params"'])
def test_a_file_that_is_no_json_is_an_erased_memory(tmp_path: Path, text: str,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    """Damaged or nested deeper than the decoder goes (that one raised RecursionError out of the
    device's creation), or JSON that is no object of sections (a number or null made every kind's
    creation fail with ``TypeError: argument of type 'int' is not iterable``, a list made the
    first save raise): the memory reads as erased, the device decides what that means, and one
    line on stderr names the file."""
    (tmp_path / "drive.nvram.json").write_text(text)
    memory = NonVolatileMemory.for_device(tmp_path, "drive")
    try:
        assert memory.corrupt and memory.sections() == []
    finally:
        memory.close()
    assert f"devsim: memory {tmp_path / 'drive.nvram.json'}: unreadable (" in capsys.readouterr().err


def test_the_first_save_over_an_unreadable_file_keeps_it_aside(tmp_path: Path,
                                                              capsys: pytest.CaptureFixture[str]) -> None:
    """A truncated file (a disk that filled up, a hand edit) is the user's data: before the fix
    the device's first save replaced it with the erased image plus that one section, so the
    programs and parameters it held were gone."""
    damaged = b'{"params": {"41": 100.0}, "programs": {"1": ["G1 X10"'
    path = tmp_path / "drive.nvram.json"
    path.write_bytes(damaged)
    (tmp_path / "drive.nvram.json.unreadable").write_bytes(b"an older one")
    memory = NonVolatileMemory.for_device(tmp_path, "drive")
    assert path.read_bytes() == damaged  # nothing moves before a save
    memory.put("params", {"41": 5})
    memory.close()
    assert (tmp_path / "drive.nvram.json.unreadable.1").read_bytes() == damaged
    assert (tmp_path / "drive.nvram.json.unreadable").read_bytes() == b"an older one"
    assert json.loads(path.read_text()) == {"params": {"41": 5}}
    assert f"kept as {tmp_path / 'drive.nvram.json.unreadable.1'}" in capsys.readouterr().err
    again = NonVolatileMemory.for_device(tmp_path, "drive")  # the saved image loads, nothing moves
    again.put("params", {"41": 6})
    again.close()
    assert sorted(p.name for p in tmp_path.glob("*.unreadable*")) == ["drive.nvram.json.unreadable",
                                                                       "drive.nvram.json.unreadable.1"]


def test_a_directory_in_place_of_the_file_is_left_alone(tmp_path: Path) -> None:
    (tmp_path / "drive.nvram.json").mkdir()
    memory = NonVolatileMemory.for_device(tmp_path, "drive")
    assert memory.corrupt
    memory.put("params", {"41": 5})  # the file system refuses the save; the device goes on
    assert memory.behind and memory.get("params") == {"41": 5}
    memory.behind = False
    memory.close()
    assert (tmp_path / "drive.nvram.json").is_dir() and not list(tmp_path.glob("*.unreadable*"))


@pytest.mark.parametrize("name", ["../escaped", "a/b", ".hidden", "", "x" * 200])
def test_names_stay_inside_the_state_dir(tmp_path: Path, name: str) -> None:
    with pytest.raises(ValueError, match="cannot name a file"):
        NonVolatileMemory.for_device(tmp_path, name)
    with pytest.raises(ValueError):
        check_name(name)
    assert list(tmp_path.iterdir()) == []


def test_a_section_shares_no_mutable_value_with_what_was_put_or_got() -> None:
    memory = NonVolatileMemory(None)
    data = {"params": {"41": 100.0, "list": [1, [2, 3]], "pair": (4, [5])}, "odd": {6, 7}, "raw": bytearray(b"x")}
    memory.put("image", data)
    data["params"]["list"][1].append(99)
    data["params"]["pair"][1].append(99)
    data["odd"].add(8)
    data["raw"] += b"y"
    got = memory.get("image")
    assert got == {"params": {"41": 100.0, "list": [1, [2, 3]], "pair": (4, [5])}, "odd": {6, 7}, "raw": bytearray(b"x")}
    got["params"]["list"].append(0)
    got["odd"].add(9)
    assert memory.get("image") == {"params": {"41": 100.0, "list": [1, [2, 3]], "pair": (4, [5])}, "odd": {6, 7},
                                   "raw": bytearray(b"x")}
    default = {"a": [1]}
    assert memory.get("missing", default) == default and memory.get("missing", default)["a"] is not default["a"]


@pytest.mark.parametrize("kind", ["gms96", "poselesta", "ip247"])
def test_a_memory_image_of_the_wrong_shape_is_refused_naming_its_file(tmp_path: Path, kind: str) -> None:
    """Sections of another shape than the kind stores (a hand edit, another kind's file): before
    the fix ``devsim run`` stopped with ``cannot create the devices: AttributeError: 'str' object
    has no attribute 'get'``, no file named.  Now the error names the file, which is left as it
    was, and the memory's lock is released.  (The SERS answers such a file as its EEPROM would,
    a failed checksum: tests/sers/test_memory.py.)"""
    path = tmp_path / f"{kind}.nvram.json"
    text = json.dumps({section: "x" for section in ("program", "eeprom", "md", "programs", "offsets")})
    path.write_text(text)
    message = str(refused_memory(tmp_path, kind))
    assert message.startswith(f"{path}: this memory image does not fit the kind '{kind}' (")
    assert message.endswith("); fix or delete the file") and "Error: " in message
    assert path.read_text() == text
    NonVolatileMemory.for_device(tmp_path, kind).close()  # the refusal released the lock


def test_a_stored_number_a_kind_cannot_compute_with_is_unfit_too(tmp_path: Path) -> None:
    """A number that overflows in a kind's load names the file as well (fuzzed: a GMS96 EEPROM
    value of -1e300 failed the start with a bare ``OverflowError: (34, 'Numerical result out of
    range')``; since the GMS96 refuses a stored N value that is no integer, a POSELESTA parameter
    of 400 digits is the one that overflows, in ``math.isfinite``)."""
    path = tmp_path / "poselesta.nvram.json"
    path.write_text('{"params": {"5": 1' + "0" * 400 + "}}")
    refused_memory(tmp_path, "poselesta", match=r"poselesta.nvram.json: .*\(OverflowError: ")


def test_the_memory_of_another_kind_is_refused_and_left_as_it_is(tmp_path: Path) -> None:
    """(Fuzzed: a device named as one of another kind before, on the same state dir, read that
    one's sections as its own: a POSELESTA took a SERS's P41, P44 ... as its parameters, and its
    first save replaced the SERS's parameters.)  An image names the kind it was written for."""
    from devsim.core.nvram import KIND_KEY, OtherKindsMemory

    memory = NonVolatileMemory.for_device(tmp_path, "x", "sers")
    memory.put("params", {"41": 100.0})
    memory.close()
    path = tmp_path / "x.nvram.json"
    text = path.read_text()
    assert json.loads(text) == {KIND_KEY: "sers", "params": {"41": 100.0}}
    with pytest.raises(OtherKindsMemory, match=r"x.nvram.json: holds the memory of a 'sers' device, not of a 'poselesta'"):
        NonVolatileMemory.for_device(tmp_path, "x", "poselesta")
    assert path.read_text() == text
    again = NonVolatileMemory.for_device(tmp_path, "x", "sers")  # the refusal released the lock
    assert again.sections() == ["params"] and again.get(KIND_KEY) is None
    again.close()
    path.write_text('{"params": {"41": 5}}')  # written before images named their kind: taken as it is
    old = NonVolatileMemory.for_device(tmp_path, "x", "poselesta")
    assert old.get("params") == {"41": 5}
    old.close()


@pytest.mark.parametrize("key", ["0", "3", "-3", "99", "1234567890123456789"])
def test_a_number_key_as_str_writes_it_is_its_number(key: str) -> None:
    assert stored_key(key, "entry") == int(key)


@pytest.mark.parametrize("key", ["٣", "²", "３", "1_0", " 3", "3 ", "+3", "03", "-0", "0x3", "3.0", "", "-",
                                 "12345678901234567890", 3, None])
def test_a_number_key_no_device_writes_is_refused(key: object) -> None:
    """``int()`` reads other scripts' digits, ``_``, blanks, a sign and leading zeros: a key a
    device never writes, and one that could be a second entry for a number already stored."""
    with pytest.raises(ValueError, match="is no number the device writes"):
        stored_key(key, "entry")


def test_numbered_entries_are_checked_against_what_the_device_keeps() -> None:
    assert numbered({"3": "a", "10": "b"}, "program", range(100)) == {3: "a", 10: "b"}
    with pytest.raises(ValueError, match="stored program 100 is none the device stores"):
        numbered({"100": "a"}, "program", range(100))
    with pytest.raises(ValueError, match="are no numbered entries"):
        numbered([1], "program")
    with pytest.raises(ValueError, match="stored value True is none the device stores"):
        stored_whole(True, "value")
