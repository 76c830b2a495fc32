"""``devsim wireshark --install``: the dissectors and the extcap launcher where Wireshark looks.

Wireshark says where its personal folders are (``tshark -G folders``, :func:`folders`): the Lua
dissectors (:func:`devsim.wireshark.install`) go to "Personal Lua Plugins", the extcap launcher
(:func:`launcher_text`, a small shell script that runs ``devsim extcap`` with this interpreter,
:mod:`devsim.wireshark.extcap`) to "Personal Extcap path" (Wireshark 4.2 and later) or, where
Wireshark names none (4.0), the ``extcap`` folder of its personal configuration, which it
searches too.  Both follow ``WIRESHARK_CONFIG_DIR`` and ``HOME`` as Wireshark itself does.
``--dir D`` installs under ``D`` instead (``D/plugins``, ``D/extcap``).
"""

from __future__ import annotations

import os
import shlex
import site
import subprocess
import sys
from pathlib import Path

from devsim.wireshark import install as install_dissectors

__all__ = ["LAUNCHER", "Installed", "extcap_dir", "folders", "install", "launcher_text", "lua_dir", "parse_folders"]

#: The launcher's file name in the extcap folder.
LAUNCHER = "devsim-extcap"


def parse_folders(text: str) -> dict[str, str]:
    """``tshark -G folders`` (``Name:<TAB>path`` lines) as a dict (the first of a repeated name)."""
    found: dict[str, str] = {}
    for line in text.splitlines():
        name, sep, path = line.partition(":")
        if sep and path.strip():
            found.setdefault(name.strip(), path.strip())
    return found


def folders(tshark: str = "tshark") -> dict[str, str]:
    """Wireshark's folders as tshark reports them; ``OSError`` when tshark cannot say."""
    try:
        result = subprocess.run([tshark, "-G", "folders"], capture_output=True, text=True, timeout=60,
                                stdin=subprocess.DEVNULL, check=False)
    except (OSError, subprocess.TimeoutExpired) as exc:
        raise OSError(f"cannot run {tshark} -G folders: {exc}") from None
    found = parse_folders(result.stdout)
    if "Personal Lua Plugins" not in found:
        raise OSError(f"{tshark} -G folders names no personal Lua plugins folder: {result.stderr.strip()[:200]}")
    return found


def lua_dir(found: dict[str, str]) -> Path:
    return Path(found["Personal Lua Plugins"])


def extcap_dir(found: dict[str, str]) -> Path:
    """The personal extcap folder: named by Wireshark 4.2+, the configuration's ``extcap`` before."""
    named = found.get("Personal Extcap path")
    return Path(named) if named else Path(found["Personal configuration"]) / "extcap"


def launcher_text(python: str, path: str | None) -> str:
    """The extcap launcher: runs ``python -m devsim extcap`` with Wireshark's arguments (``path``:
    where devsim is imported from, put first on ``PYTHONPATH``; None when the interpreter finds it)."""
    lines = ["#!/bin/sh", "# devsim's Wireshark extcap: installed by 'devsim wireshark --install'"]
    if path is not None:
        lines.append(f'PYTHONPATH={shlex.quote(path)}${{PYTHONPATH:+:$PYTHONPATH}}; export PYTHONPATH')
    lines.append(f'exec {shlex.quote(python)} -m devsim extcap "$@"')
    return "\n".join(lines) + "\n"


def _import_path() -> str | None:
    """Where this devsim is imported from, when the interpreter would not find it by itself (a
    source checkout on ``PYTHONPATH``)."""
    here = str(Path(__file__).resolve().parents[2])
    installed = {str(Path(p).resolve()) for p in [*site.getsitepackages(), site.getusersitepackages()]}
    return None if here in installed else here


class Installed:
    """What :func:`install` wrote: the dissector files and the launcher."""

    def __init__(self, dissectors: list[Path], launcher: Path) -> None:
        self.dissectors = dissectors
        self.launcher = launcher


def install(directory: str | os.PathLike[str] | None = None, tshark: str = "tshark") -> Installed:
    """Copy the dissectors and write the launcher: into Wireshark's personal folders, or under
    ``directory`` (``plugins`` and ``extcap``)."""
    if directory is not None:
        lua, extcap = Path(directory) / "plugins", Path(directory) / "extcap"
    else:
        found = folders(tshark)
        lua, extcap = lua_dir(found), extcap_dir(found)
    dissectors = install_dissectors(lua)
    extcap.mkdir(parents=True, exist_ok=True)
    launcher = extcap / LAUNCHER
    launcher.write_text(launcher_text(sys.executable, _import_path()), encoding="utf-8")
    launcher.chmod(0o755)
    return Installed(dissectors, launcher)
