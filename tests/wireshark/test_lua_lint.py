"""devsim's Lua dissectors pass luacheck (Lua 5.2, the Wireshark API as read-only globals): no
global written by mistake, no undefined name, no unused variable (the callbacks' unused arguments
aside, which Wireshark's interface fixes)."""

from __future__ import annotations

import subprocess

from tests.support.programs import needs_program
from tests.wireshark.captures import DISSECTOR

#: What Wireshark's Lua API puts in the global table (the parts the dissectors use).
WIRESHARK_GLOBALS = ["Proto", "ProtoField", "ProtoExpert", "expert", "base", "ftypes", "DissectorTable", "Dissector",
                     "ByteArray", "wtap", "P2P_DIR_SENT", "P2P_DIR_RECV", "bit32"]


def test_the_dissectors_pass_luacheck() -> None:
    luacheck = needs_program("luacheck")
    files = sorted(str(path) for path in DISSECTOR.parent.glob("*.lua"))
    result = subprocess.run([luacheck, "--std", "lua52", "--read-globals", *WIRESHARK_GLOBALS, "--no-max-line-length",
                             "--no-unused-args", "--no-color", "--codes", *files],
                            capture_output=True, text=True, timeout=120, check=False)
    assert result.returncode == 0, result.stdout
