"""The configuration file ``devsim run gms96 --config FILE`` reads: an N parameter's key has only
space/TAB around it; a broadcast address is 255 or none."""

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


@pytest.mark.parametrize("value", ["0", "3", "31", "32", "254", "256", "-1", "1000000", "true", "255.5"])
def test_a_broadcast_address_other_than_255_is_refused_as_the_file_is_loaded(tmp_path: Path, value: str) -> None:
    """FT1.2's address field is one octet and IEC 60870-5-2's broadcast in it is 255 (spec §2.3
    [R]; the manual has none).  Before, any integer was taken: 3, the card's own address, made
    every other card on the line execute and not answer frames to card 3; 256 named no octet."""
    path = tmp_path / "gms.yaml"
    path.write_text(f"link: {{broadcast_address: {value}}}\n", encoding="utf-8")
    with pytest.raises(ConfigError, match=r"gms\.yaml:1: link\.broadcast_address: Input should be 255"):
        load_config(path, Gms96Config)
    for kept, expected in (("255", 255), ("null", None)):
        path.write_text(f"link: {{broadcast_address: {kept}}}\n", encoding="utf-8")
        assert load_config(path, Gms96Config).link.broadcast_address == expected
