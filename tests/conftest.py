"""Suite-wide hooks: the ``manual`` marker's arguments are checked, and counted per kind; the
simulators the tests start keep their control sockets in a runtime directory of the test run's
own (``XDG_RUNTIME_DIR``), apart from the user's.  A run started in the background by a shell
without job control (``pytest &`` in a script) inherits SIGINT ignored, and so would every
simulator it starts, which the tests stop with Ctrl-C's signal: the run takes SIGINT back.

A test marked ``@pytest.mark.manual("§2.6.2.1", "the printer port always runs at 1200 baud")``
checks one statement of its kind's manual (the kind is the test's folder under tests/).  The
summary at the end of a run says how many statements and sections each kind has under test.

Tests that need a program outside Python ask for it with
:func:`tests.support.programs.needs_program`; where it is missing they are skipped, and the run
ends with one line naming the missing programs and the command that installs them.
"""

from __future__ import annotations

import os
import re
import shutil
import signal
import tempfile
from collections import defaultdict

import pytest

from tests.support.programs import install_line, missing_names

SECTION = re.compile(r"§\d+(\.\d+)*[a-z]?( .+)?$")


_runtime_dir = tempfile.mkdtemp(prefix="devsim-rt-")  # short: a Unix socket path holds 107 bytes
os.environ["XDG_RUNTIME_DIR"] = _runtime_dir
os.environ.pop("DEVSIM_CONTROL", None)
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:  # (inherited: see above)
    signal.signal(signal.SIGINT, signal.default_int_handler)


def pytest_unconfigure() -> None:
    shutil.rmtree(_runtime_dir, ignore_errors=True)


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    for item in items:
        for mark in item.iter_markers("manual"):
            if len(mark.args) != 2 or not SECTION.match(str(mark.args[0])) or not str(mark.args[1]).strip():
                raise pytest.UsageError(
                    f"{item.nodeid}: @pytest.mark.manual takes (section, statement), "
                    f"section like '§2.6.2.1'; got {mark.args!r}"
                )
            # (carried by the test's reports: under pytest-xdist the workers collect, not the controller)
            item.user_properties.append(("manual", (item.path.parent.name, str(mark.args[0]).split()[0])))


def pytest_terminal_summary(terminalreporter: pytest.TerminalReporter) -> None:
    _manual_summary(terminalreporter)
    _missing_programs_summary(terminalreporter)


def _missing_programs_summary(terminalreporter: pytest.TerminalReporter) -> None:
    """One line: how many tests were skipped for want of which programs, and how to install them."""
    names: list[str] = []
    count = 0
    for report in terminalreporter.stats.get("skipped", []):
        longrepr = getattr(report, "longrepr", None)
        reason = longrepr[2] if isinstance(longrepr, tuple) and len(longrepr) == 3 else ""
        found = missing_names(str(reason))
        count += bool(found)
        names += [name for name in found if name not in names]
    if names:
        terminalreporter.write_line(
            f"{count} tests skipped: {', '.join(names)} not installed here"
            f" (install: {install_line(names)}; CI=true makes these skips failures)",
            yellow=True,
        )


def _manual_summary(terminalreporter: pytest.TerminalReporter) -> None:
    """Per kind: how many manual statements the tests that ran check, in how many sections."""
    walk: dict[str, dict[str, int]] = defaultdict(lambda: defaultdict(int))
    seen: set[str] = set()
    for reports in terminalreporter.stats.values():
        for report in reports:
            nodeid = getattr(report, "nodeid", None)
            if nodeid is None or nodeid in seen:
                continue
            marks = [value for name, value in getattr(report, "user_properties", ()) if name == "manual"]
            if marks:
                seen.add(nodeid)
            for kind, section in marks:
                walk[kind][section] += 1
    if not walk:
        return
    terminalreporter.section("manual statements under test")
    for kind, sections in sorted(walk.items()):
        terminalreporter.write_line(
            f"{kind}: {sum(sections.values())} statements in {len(sections)} sections"
        )
