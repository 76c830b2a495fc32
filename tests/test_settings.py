"""Configuration tables (devsim.core.settings): checks, messages and the file lines they get."""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Annotated, Any, Literal

import pytest

from devsim.core.config import ConfigError, load_config, load_yaml, validate
from devsim.core.settings import Check, Invalid, Keys, Meta, Settings, doc, field, rows


def _even(value: int) -> int:
    if value % 2:
        raise ValueError("must be even")
    return value


class Rule(Settings, rename={"source": "from"}):
    """a rule"""

    source: Annotated[str, doc("a bit")]
    invert: bool = False


class Geometry(Settings):
    """where things are"""

    cam: tuple[float, float] | None = (-2.0, -1.0)
    marks: list[float] = []


class Config(Settings, kw_only=True):
    """a device"""

    address: Annotated[int, Meta(ge=0, le=31), doc("switches")] = 3
    step: Annotated[int, Check(_even)] = 2
    gain: Annotated[float, Meta(gt=0)] = 0.5
    mode: Literal["S", "E"] = "S"
    name: str
    params: Annotated[dict[Any, float | int], Keys(int, "number")] = {}
    axis: Geometry = field(default_factory=Geometry)
    rules: list[Rule] = []

    @classmethod
    def screen(cls, data: Mapping[Any, Any]) -> None:
        if "foo" in data:
            raise ValueError("this looks like a foo file")


CONFIG = Config


def test_defaults_conversions_and_values() -> None:
    values = CONFIG.parse({"name": "x", "gain": 2, "params": {"10": 3, 11: 1.5}, "rules": [{"from": "E0.1"}]})
    assert values.gain == 2.0 and isinstance(values.gain, float)
    assert values.params == {10: 3, 11: 1.5} and isinstance(values.params[10], int)
    assert values.axis.cam == (-2.0, -1.0) and values.axis.marks == []
    assert values.rules[0].source == "E0.1" and values.rules[0].invert is False
    assert values.dump()["rules"] == [{"from": "E0.1", "invert": False}]  # keyed as in a file
    assert CONFIG.parse(values.dump()) == values  # a dump validates again to the same values
    assert values.replace(address=5).address == 5 and values.address == 3


@pytest.mark.parametrize(
    ("data", "problem"),
    [
        ({"name": "x", "address": 32}, (("address",), "Input should be less than or equal to 31")),
        ({"name": "x", "address": "a"}, (("address",), "Input should be a valid integer, unable to parse string as an integer")),
        ({"name": "x", "address": 1.5}, (("address",), "Input should be a valid integer, got a number with a fractional part")),
        ({"name": "x", "address": True}, (("address",), "Input should be a valid integer")),
        ({"name": "x", "step": 3}, (("step",), "must be even")),
        ({"name": "x", "gain": 0}, (("gain",), "Input should be greater than 0")),
        ({"name": "x", "gain": float("nan")}, (("gain",), "not a finite number (NaN and infinity are refused)")),
        ({"name": "x", "mode": "X"}, (("mode",), "Input should be 'S' or 'E'")),
        ({}, (("name",), "Field required")),
        ({"name": "x", "colour": 1}, (("colour",), "unknown field")),
        ({"name": "x", "params": {"N1": 1}}, (("params", "N1"), "invalid literal for int() with base 10: 'N1'")),
        ({"name": "x", "axis": {"cam": [1]}}, (("axis", "cam"), "Input should be a list of two values")),
        ({"name": "x", "rules": [{"from": "E0.1"}, {"invert": "maybe"}]}, (("rules", 1, "from"), "Field required")),
        ({"foo": 1}, ((), "this looks like a foo file")),
    ],
)
def test_each_problem_is_named(data: dict[str, object], problem: tuple[tuple[object, ...], str]) -> None:
    with pytest.raises(Invalid) as info:
        CONFIG.parse(data)
    assert info.value.problems[0] == problem


def test_problems_in_a_file_name_their_line(tmp_path: Path) -> None:
    path = tmp_path / "device.yaml"
    path.write_text("name: x\naxis:\n  marks: [1, 2]\nrules:\n  - from: E0.1\n  - from: E0.2\n    invert: maybe\n")
    with pytest.raises(ConfigError) as info:
        load_config(path, CONFIG)
    assert str(info.value) == f"{path}:7: rules.2.invert: Input should be a valid boolean"
    path.write_text("name: x\nparams:\n  10: .inf\n")
    with pytest.raises(ConfigError, match=r":3: params.10: not a finite number"):
        load_config(path, CONFIG)
    assert validate(load_yaml("d.yaml", "name: y\n"), CONFIG, "d.yaml").name == "y"


def test_rows_document_every_key() -> None:
    keys = [row[0] for row in rows(CONFIG)]
    assert keys == ["address", "step", "gain", "mode", "name", "params", "axis", "axis.cam", "axis.marks", "rules"]
    assert dict((r[0], r[1]) for r in rows(CONFIG))["axis.cam"] == "[float, float] | None"


def test_a_simulator_starts_without_the_error_collector() -> None:
    """A valid configuration takes msgspec's compiled path only: the piecewise search for every
    problem (devsim.core.typed_errors) is imported when a configuration is wrong."""
    code = (
        "import sys; from devsim.core.registry import device_class;"
        "from devsim.core.clock import VirtualClock;"
        "[device_class(k)(clock=VirtualClock(), config=device_class(k).config_model.parse({}).dump())"
        " for k in ('sers', 'gms96', 'poselesta', 'ip247', 'pcd4h3')];"
        "print('devsim.core.typed_errors' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"


def test_a_simulator_starts_without_a_second_typed_data_library_or_yaml() -> None:
    """One typed-data library (msgspec): building every kind and importing the CLI, the runtime
    and the pty transport loads no pydantic, no dataclasses and (without a file) no YAML."""
    code = (
        "import sys; from devsim.core.registry import device_class;"
        "import devsim.cli, devsim.transports.pty, devsim.runtime;"
        "from devsim.core.clock import VirtualClock;"
        "[device_class(k)(clock=VirtualClock(), config=device_class(k).config_model.parse({}).dump())"
        " for k in ('sers', 'gms96', 'poselesta', 'ip247', 'pcd4h3')];"
        "print(sorted(m for m in sys.modules if m.split('.')[0] in {'pydantic', 'yaml', 'dataclasses', 'attrs'}))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"
