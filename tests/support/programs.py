"""Programs outside Python that some tests start or talk to (tshark, mosquitto and its clients,
Node.js with npm, tmux, chromium for the web page's browser test) and the cairo library (the monitor's screenshot): found, or the test is
skipped, and the run ends with one line naming what was missing and the command that installs it
(``tests/conftest.py``).  Under ``CI=true`` (``.ci/run`` sets it and installs them all) a missing
program is a failure, so CI runs every test.

    path = needs_program("tshark")                       # in a test or a fixture
    needs_program("mosquitto", "mosquitto_sub")          # several: all must be there
"""

from __future__ import annotations

import ctypes.util
import os
import shutil
from pathlib import Path

import pytest

__all__ = ["PACKAGES", "REASON", "install_line", "missing_names", "missing_reason", "needs_library", "needs_program", "strict"]

#: Each program or library, and the Debian/Ubuntu package that brings it (``.ci/run`` installs
#: the same packages).
PACKAGES = {
    "tshark": "tshark",
    "luacheck": "lua-check",
    "mosquitto": "mosquitto",
    "mosquitto_passwd": "mosquitto",
    "mosquitto_sub": "mosquitto-clients",
    "mosquitto_pub": "mosquitto-clients",
    "node": "nodejs",
    "npm": "npm",
    "tmux": "tmux",
    "chromium": "chromium",
    "ss": "iproute2",
    "libcairo": "libcairo2",
}
#: Where Debian puts daemons such as mosquitto (often not on a user's PATH).
_SBIN = Path("/usr/sbin")
#: The start of every skip reason given here (the summary finds the skips by it).
REASON = "not installed here:"


def strict() -> bool:
    """Whether a missing program fails the test (CI) instead of skipping it."""
    return os.environ.get("CI", "").lower() == "true"


def _program(name: str) -> str | None:
    found = shutil.which(name)
    if found is None and os.access(_SBIN / name, os.X_OK):
        found = str(_SBIN / name)
    return found


def missing_reason(names: list[str]) -> str:
    """The skip reason for missing ``names`` (parsed back by :func:`missing_names`)."""
    return f"{REASON} {', '.join(names)}"


def missing_names(reason: str) -> list[str]:
    """The names in a skip reason of :func:`missing_reason` ([] for any other reason)."""
    _, found, rest = reason.partition(REASON)
    return [name.strip() for name in rest.split(",") if name.strip()] if found else []


def install_line(names: list[str]) -> str:
    """The one command that installs ``names``."""
    packages = list(dict.fromkeys(PACKAGES.get(name, name) for name in names))
    return f"sudo apt-get install {' '.join(packages)}"


def _refuse(names: list[str]) -> None:
    reason = missing_reason(names)
    if strict():
        pytest.fail(f"{reason} (CI=true: a missing program is a failure; {install_line(names)})", pytrace=False)
    pytest.skip(reason)


def needs_program(name: str, *also: str) -> str:
    """The path of program ``name`` (``also`` must be installed too); skips the test (fails it
    under CI=true) when any is missing."""
    paths = {program: _program(program) for program in (name, *also)}
    absent = [program for program, path in paths.items() if path is None]
    if absent:
        _refuse(absent)
    return str(paths[name])


def needs_library(name: str) -> None:
    """Skip the test (fail it under CI=true) unless the shared library ``name`` (e.g. ``cairo``)
    can be loaded."""
    if ctypes.util.find_library(name) is None:
        _refuse([f"lib{name}"])
