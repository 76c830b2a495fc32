"""YAML configuration loading: line numbers for every kind of error."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import msgspec
import pytest

from devsim.core.config import ConfigError, load_config, load_yaml, plain, validate
from devsim.core.typed import Typed
from devsim.devices.sers.config import SersConfig


class Step(Typed):
    at: float
    name: str


class Scenario(Typed):
    title: str
    steps: list[Step]


def write(tmp_path: Path, text: str, name: str = "config.yaml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def error_of(path: Path, model: type[Typed] = SersConfig) -> str:
    with pytest.raises(ConfigError) as info:
        load_config(path, model)
    message = str(info.value)
    assert "\n" not in message
    return message


def test_valid_sers_config(tmp_path: Path) -> None:
    path = write(
        tmp_path,
        "address: 3\nbaud: 19200\nparams:\n  P1017: 2\naxis:\n  limit_left: -1000\n  limit_right: 50000\n",
    )
    config = load_config(path, SersConfig)
    assert config.address == 3
    assert config.baud == 19200
    assert config.params == {"P1017": 2}
    assert config.axis.limit_right == 50000


def test_top_level_field_error_names_file_line_field(tmp_path: Path) -> None:
    path = write(tmp_path, "# DIP switches\naddress: 3\nbaud: 9601\n")
    message = error_of(path)
    assert message.startswith(f"{path}:3: baud: baud must be one of 1200, ")
    assert "Value error" not in message


def test_nested_field_line(tmp_path: Path) -> None:
    path = write(tmp_path, "address: 1\naxis:\n  limit_left: -5\n\n  limit_right: far\n")
    assert error_of(path).startswith(f"{path}:5: axis.limit_right: Input should be a valid number")


def test_unknown_nested_field(tmp_path: Path) -> None:
    path = write(tmp_path, "axis:\n  limit_left: 1\n  limitt_right: 2\n")
    assert error_of(path) == f"{path}:3: axis.limitt_right: unknown field"


def test_dict_value_error_has_one_message_per_field(tmp_path: Path) -> None:
    path = write(tmp_path, "params:\n  P1: 1\n  P2: lots\n")
    with pytest.raises(ConfigError) as info:
        load_config(path, SersConfig)
    assert info.value.messages == [f"{path}:3: params.P2: Input should be a valid number, unable to parse string as a number"]


def test_range_error(tmp_path: Path) -> None:
    path = write(tmp_path, "address: 128\n")
    assert error_of(path) == f"{path}:1: address: Input should be less than or equal to 127"


def test_list_item_and_missing_field_lines(tmp_path: Path) -> None:
    path = write(tmp_path, "title: t\nsteps:\n  - at: 1\n    name: a\n  - at: 2\n  - at: soon\n    name: c\n")
    with pytest.raises(ConfigError) as info:
        load_config(path, Scenario)
    assert info.value.messages == [
        f"{path}:5: steps.2.name: Field required",
        f"{path}:6: steps.3.at: Input should be a valid number, unable to parse string as a number",
    ]
    assert str(info.value) == f"{path}:5: steps.2.name: Field required (and 1 more)"


def test_missing_top_level_field_reported_at_line_1(tmp_path: Path) -> None:
    path = write(tmp_path, "steps: []\n")
    assert error_of(path, Scenario) == f"{path}:1: title: Field required"


def test_yaml_syntax_error_line(tmp_path: Path) -> None:
    path = write(tmp_path, "address: 1\nbaud: 9600\naxis:\n  limit_left: 1\n bad: 2\n")
    message = error_of(path)
    assert message.startswith(f"{path}:5: ")


@pytest.mark.parametrize("text", ["autostart: " + "[" * 100_000, "autostart: " + "[" * 400 + "]" * 400,
                                  "- " * 3000 + "x"])
def test_yaml_nested_deeper_than_the_reader_goes(tmp_path: Path, text: str) -> None:
    """PyYAML composes nested collections recursively: a RecursionError's traceback before."""
    path = write(tmp_path, text + "\n")
    assert error_of(path) == f"{path}: nested deeper than this reader goes"


def test_unclosed_flow_sequence(tmp_path: Path) -> None:
    path = write(tmp_path, "options: [E50, IO\naddress: 2\n")
    assert error_of(path).startswith(f"{path}:2: ")


def test_duplicate_key_is_an_error(tmp_path: Path) -> None:
    path = write(tmp_path, "baud: 9600\naddress: 1\nbaud: 19200\n")
    assert error_of(path) == f"{path}:3: duplicate key 'baud' (first on line 1)"


def test_empty_file_gives_defaults(tmp_path: Path) -> None:
    path = write(tmp_path, "# nothing set\n")
    assert load_config(path, SersConfig) == SersConfig()


def test_top_level_not_a_mapping(tmp_path: Path) -> None:
    path = write(tmp_path, "- 1\n- 2\n")
    assert error_of(path) == f"{path}:1: expected a mapping at the top level, got a list"


def test_missing_file(tmp_path: Path) -> None:
    assert error_of(tmp_path / "nope.yaml") == f"{tmp_path / 'nope.yaml'}: no such file"


def test_load_yaml_keeps_lines_and_plain_drops_them() -> None:
    data = load_yaml("x.yaml", "a: 1\nb:\n  - 2\n  - c: 3\n")
    assert data.key_lines == {"a": 1, "b": 2}
    assert data["b"].item_lines == [3, 4]
    assert data["b"][1].key_lines == {"c": 4}
    assert plain(data) == {"a": 1, "b": [2, {"c": 3}]}
    assert type(plain(data)) is dict


def test_merge_keys_still_work() -> None:
    data = load_yaml("m.yaml", "base: &b {at: 1, name: x}\nstep:\n  <<: *b\n  name: y\n")
    assert plain(data)["step"] == {"at": 1, "name": "y"}


def test_validate_with_text_source() -> None:
    with pytest.raises(ConfigError, match=r"^plant.yaml:2: baud: "):
        validate(load_yaml("plant.yaml", "address: 1\nbaud: 7\n"), SersConfig, "plant.yaml")


def test_readme_example_config_is_valid(tmp_path: Path) -> None:
    readme = (Path(__file__).resolve().parents[1] / "docs" / "connect.md").read_text(encoding="utf-8")
    block = readme.split("```yaml\n", 1)[1].split("```", 1)[0]
    config = load_config(write(tmp_path, block, "sers.yaml"), SersConfig)
    assert config.params == {"P1017": 2}


class Axis(Typed):
    limit: float = 0.0
    extra: dict[str, Any] = {}


class Model(Typed):
    axis: Axis = msgspec.field(default_factory=Axis)


@pytest.mark.parametrize("value", [".nan", ".inf", "-.inf", "1e400", "'-1e999'"])
def test_non_finite_numbers_are_refused_with_their_line(tmp_path: Path, value: str) -> None:
    path = tmp_path / "c.yaml"
    path.write_text(f"axis:\n  limit: {value}\n")
    with pytest.raises(ConfigError, match=r"c.yaml:2: axis.limit: not a finite number"):
        load_config(path, Model)
    path.write_text(f"axis:\n  extra: {{P51: {value}}}\n")
    if value in ("1e400", "'-1e999'"):
        load_config(path, Model)  # text in a free mapping: the device's own table parses it
    else:
        with pytest.raises(ConfigError, match=r"c.yaml:2: axis.extra.P51: not a finite number"):
            load_config(path, Model)


def test_an_unknown_gms96_variant_is_refused_with_its_line(tmp_path: Path) -> None:
    """(Fuzzed: ``variant: abc`` passed the file's checks and ``devsim run gms96`` stopped with
    ``cannot create the devices: KeyError: 'ABC'``.)"""
    from devsim.devices.gms96.config import Gms96Config

    path = write(tmp_path, "dil: {}\nvariant: abc\n")
    assert error_of(path, Gms96Config).startswith(f"{path}:2: variant: no such variant 'abc' (variants: K1, ")
    assert load_config(write(tmp_path, "variant: g96-ksa15-2r\n"), Gms96Config).variant == "g96-ksa15-2r"
