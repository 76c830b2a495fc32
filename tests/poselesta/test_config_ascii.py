"""The configuration file ``devsim run poselesta --config FILE`` reads: its parameter numbers and
key codes are ASCII digits with only space/TAB around them."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from devsim.core.config import ConfigError, load_config
from devsim.devices.poselesta.config import PoselestaConfig


@pytest.mark.parametrize("key", ["\u00a048", "\u300048", "48\x1c", "\u0664\u0668", "+48", "4_8", "0x\u0664\u0668"])
def test_a_configured_key_code_is_ascii_hex(tmp_path: Path, key: str) -> None:
    """int(key, 16) read the Arabic-Indic '٤٨', '+48' and '4_8' as the key 48 (P), and skipped NBSP,
    U+3000 and FS around it."""
    path = tmp_path / "pos.yaml"
    path.write_text(f"v8_keymap: {{{json.dumps(key)}: EXIT}}\n", encoding="utf-8")
    with pytest.raises(ConfigError, match="key code"):
        load_config(path, PoselestaConfig)
    path.write_text('v8_keymap: {"48": P, " 0x2D": EXIT, 0x4E: N}\n', encoding="utf-8")
    assert load_config(path, PoselestaConfig).v8_keymap == {0x48: "P", 0x2D: "EXIT", 0x4E: "N"}


@pytest.mark.parametrize("key", ["\u00a067", "\u300067", "67\x1c", "\x8567"])
def test_a_configured_parameter_number_has_only_ascii_blanks(tmp_path: Path, key: str) -> None:
    """str.strip() took NBSP, U+3000, FS and NEL off a params key: '\\u300067' was P67."""
    path = tmp_path / "pos.yaml"
    path.write_text(f"params: {{{json.dumps(key)}: 1}}\n", encoding="utf-8")
    with pytest.raises(ConfigError, match="valid integer"):
        load_config(path, PoselestaConfig)
    path.write_text('params: {" 67": 1}\n', encoding="utf-8")
    assert load_config(path, PoselestaConfig).params == {67: 1.0}
