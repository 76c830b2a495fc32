"""devsim's Wireshark dissectors (Lua, Wireshark 3.x/4.x API) for the serial-line captures that
``--trace FILE.pcap`` writes (docs/wireshark-dissectors.md): ``devsim.lua`` decodes the devsim
header on LINKTYPE_USER0 and loads the kinds' dissectors beside it; ``<kind>_tables.lua`` are
generated from the kinds' own tables by :mod:`devsim.wireshark.generate`.

:func:`install` copies the files into a Lua plugins folder (``devsim wireshark --install`` uses
it with :func:`personal_plugins_dir`)."""

from __future__ import annotations

import os
import shutil
import sys
from pathlib import Path

__all__ = ["HERE", "install", "lua_files", "personal_plugins_dir"]

HERE = Path(__file__).resolve().parent


def lua_files() -> list[Path]:
    """The dissector files shipped with devsim: devsim.lua, the kinds' files and their tables."""
    return sorted(HERE.glob("*.lua"))


def personal_plugins_dir(home: Path | None = None) -> Path:
    """Wireshark's personal Lua plugins folder (``tshark -G folders``, "Personal Lua Plugins"):
    ``%APPDATA%\\Wireshark\\plugins`` on Windows, ``~/.local/lib/wireshark/plugins`` elsewhere."""
    if sys.platform == "win32" and home is None and os.environ.get("APPDATA"):
        return Path(os.environ["APPDATA"]) / "Wireshark" / "plugins"
    return (home or Path.home()) / ".local" / "lib" / "wireshark" / "plugins"


def install(folder: Path) -> list[Path]:
    """Copy every dissector file into ``folder`` (made if missing); the files written.  Wireshark
    loads each .lua file there on its own: the kinds' files and tables do nothing then, and
    devsim.lua loads them."""
    folder.mkdir(parents=True, exist_ok=True)
    return [Path(shutil.copy(path, folder / path.name)) for path in lua_files()]
