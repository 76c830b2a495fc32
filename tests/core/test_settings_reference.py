"""The configuration reference ``devsim doc`` prints (devsim/core/settings.py): every key, nested
keys dotted, its type as a user writes it, its default (cut at 40 characters) and its description."""

from __future__ import annotations

from typing import Annotated, Any, Literal, Optional

import msgspec
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from devsim.core.settings import Keys, Meta, Settings, doc, field, rows, type_text

#: No deadline, no speed health check: a loaded machine (or a mutation run) must not fail these.
BOUNDARY = settings(deadline=None, suppress_health_check=[HealthCheck.too_slow])


class Part(Settings):
    """A nested   part,
    over two lines."""

    low: float = 0.0


class Described(Settings):
    """has a description of its own"""

    x: int = 1


class Device(Settings, kw_only=True):
    """a device"""

    address: Annotated[int, Meta(ge=0, le=31), doc("DIP switches 1-5")] = 3
    limit: Annotated[int, Meta(ge=0)] = 7
    mode: Literal["S", "E"] = "S"
    name: str
    offset: Annotated[float, Meta(description="")] = 0.0
    table: Annotated[dict[Any, float], Keys(int, "N parameter")] = {}
    plain: dict[str, int] = {}
    cam: tuple[float, float] | None = (-2.0, -1.0)
    old: Optional[int] = None  # noqa: UP045 - the typing.Union spelling prints the same
    marks: list[float] = field(default_factory=lambda: [1.0, 2.0])
    part: Part = field(default_factory=Part)
    other: Annotated[Described, doc("the other part")] = field(default_factory=Described)
    parts: list[Part] = []


def test_every_key_with_type_default_and_description() -> None:
    assert list(rows(Device)) == [
        ("address", "int", "3", "DIP switches 1-5"),
        ("limit", "int", "7", ""),
        ("mode", "'S' | 'E'", "'S'", ""),
        ("name", "str", "", ""),
        ("offset", "float", "0.0", ""),
        ("table", "{N parameter: float}", "{}", ""),
        ("plain", "{key: int}", "{}", ""),
        ("cam", "[float, float] | None", "(-2.0, -1.0)", ""),
        ("old", "int | None", "None", ""),
        ("marks", "list[float]", "[1.0, 2.0]", ""),
        ("part", "mapping", "", "A nested part, over two lines."),
        ("part.low", "float", "0.0", ""),
        ("other", "mapping", "", "the other part"),
        ("other.x", "int", "1", ""),
        ("parts", "list[mapping]", "[]", ""),
    ]


def test_rows_under_a_prefix() -> None:
    assert list(rows(Part, "axis.")) == [("axis.low", "float", "0.0", "")]


class Bare(Settings):
    y: int = 0


class Outer(Settings):
    bare: Bare = field(default_factory=Bare)


def test_a_part_without_a_docstring_has_no_description() -> None:
    assert list(rows(Outer))[0] == ("bare", "mapping", "", "")


@BOUNDARY
@given(st.integers(0, 60))
def test_defaults_are_cut_at_40_characters(length: int) -> None:
    """Oracle: the default's repr as it is up to 40 characters, else its first 37 and '...'."""
    text = "x" * length

    Long = msgspec.defstruct("Long", [("value", str, text)], bases=(Settings,))
    shown = repr(text)
    expected = shown if len(shown) <= 40 else shown[:37] + "..."
    assert list(rows(Long)) == [("value", "str", expected, "")]


@pytest.mark.parametrize(
    ("kind", "text"),
    [
        (int, "int"),
        (Literal[1, "a"], "1 | 'a'"),
        (int | str, "int | str"),
        (list[tuple[int, str]], "list[[int, str]]"),
        (dict[str, list[int]], "{key: list[int]}"),
        (Annotated[dict[int, bool], Keys(int, "bit")], "{bit: bool}"),
        (Annotated[dict[int, bool], Meta(ge=0)], "{key: bool}"),
        (Part, "mapping"),
        ("text", "text"),
    ],
)
def test_type_text(kind: Any, text: str) -> None:
    assert type_text(kind) == text
