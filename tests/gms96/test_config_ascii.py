"""The configuration file ``devsim run gms96 --config FILE`` reads: an N parameter's key has only
space/TAB around it."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from devsim.core.config import ConfigError, load_config
from devsim.devices.gms96.config import Gms96Config


@pytest.mark.parametrize("key", ["\u00a0N10", "\u3000N10", "N10\x1c", "\x85N10", "N10\u2028"])
def test_a_configured_n_parameter_has_only_ascii_blanks(tmp_path: Path, key: str) -> None:
    """str.strip() took NBSP, U+3000, FS, NEL and U+2028 off a params key: '\\u3000N10' was N10."""
    path = tmp_path / "gms.yaml"
    path.write_text(f"params: {{{json.dumps(key)}: 300}}\n", encoding="utf-8")
    with pytest.raises(ConfigError, match="no such parameter"):
        load_config(path, Gms96Config)
    path.write_text('params: {" n10": 300}\n', encoding="utf-8")
    assert load_config(path, Gms96Config).params == {10: 300}
