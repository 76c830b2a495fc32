"""Records (devsim.core.record): what the tables and statements rely on from them."""

from __future__ import annotations

import subprocess
import sys

import pytest

from devsim.core.record import FrozenInstanceError, asdict, field, fields, is_record, record, replace


@record
class Row:
    name: str
    size: int = 1
    note: str = field(default="", compare=False)
    tags: list[str] = field(default_factory=list)


@record
class Wide(Row):
    width: float = 0.0


@record
class Key:
    name: str
    note: str = field(default="", compare=False)


@record(frozen=False)
class Counter:
    count: int = 0


def test_init_defaults_factories_and_order() -> None:
    row = Row("a")
    assert (row.name, row.size, row.note, row.tags) == ("a", 1, "", [])
    assert Row("a").tags is not row.tags
    assert [f.name for f in fields(Wide)] == ["name", "size", "note", "tags", "width"]
    assert Wide("w", 2, width=3.5).width == 3.5
    with pytest.raises(TypeError):
        Row()  # type: ignore[call-arg]


def test_equality_by_class_and_compared_fields_and_hash() -> None:
    assert Row("a", note="x") == Row("a", note="y")
    assert hash(Key("a", note="x")) == hash(Key("a", note="y")) and len({Key("a"), Key("b")}) == 2
    assert Row("a") != Row("b")
    assert Row("a") != Wide("a")  # another class never equals, whatever its fields
    assert repr(Row("a")) == "Row(name='a', size=1, note='', tags=[])"


def test_frozen_unless_asked() -> None:
    row = Row("a")
    with pytest.raises(FrozenInstanceError):
        row.name = "b"  # type: ignore[misc]
    counter = Counter()
    counter.count += 1
    assert counter.count == 1
    with pytest.raises(TypeError):
        hash(counter)


def test_replace_asdict_and_mutable_defaults_refused() -> None:
    assert replace(Row("a", 2), size=3) == Row("a", 3)
    assert asdict(Wide("w", tags=["t"])) == {"name": "w", "size": 1, "note": "", "tags": ["t"], "width": 0.0}
    assert is_record(Row("a")) and not is_record(Row)
    with pytest.raises(ValueError, match="mutable default"):

        @record
        class Bad:
            items: list[int] = []  # noqa: RUF012


def test_match_by_position() -> None:
    match Row("a", 2):
        case Row(name, size):
            assert (name, size) == ("a", 2)
        case _:
            pytest.fail("no match")


def test_a_simulator_starts_without_a_schema_library() -> None:
    """`devsim run` builds a device from its tables alone: pydantic (the control API) is imported
    only when a control server runs."""
    code = (
        "import sys; from devsim.core.registry import device_class;"
        "import devsim.cli, devsim.transports.pty, devsim.runtime;"
        "from devsim.core.clock import VirtualClock;"
        "[device_class(k)(clock=VirtualClock(), config=device_class(k).config_model.parse({}).dump())"
        " for k in ('sers', 'gms96', 'poselesta')];"
        "print(sorted(m for m in sys.modules if m.split('.')[0] in {'pydantic', 'yaml', 'dataclasses'}))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "['dataclasses']"  # the module only: record borrows field() from it
