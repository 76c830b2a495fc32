"""The Lua tables the dissectors read are generated from the kinds' own tables and committed:
they must be current (``python -m devsim.wireshark.generate`` rewrites them)."""

from __future__ import annotations

import pytest

from devsim.wireshark import generate


@pytest.mark.parametrize("name", sorted(generate.GENERATORS))
def test_committed_tables_are_current(name: str) -> None:
    path = generate.HERE / name
    assert path.read_text(encoding="utf-8") == generate.render(name), (
        f"{path.name} is stale: run `python -m devsim.wireshark.generate` and look at the diff"
    )


def test_lua_strings_escape_quotes_backslashes_and_control_characters() -> None:
    assert generate.lua_value('a "b" \\ c\n\x01') == '"a \\"b\\" \\\\ c\\n\\001"'
    assert generate.lua_value({2: "x", "k": [1, True]}) == '{\n  [2] = "x",\n  ["k"] = {1, true},\n}'
