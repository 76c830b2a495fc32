"""The README's command for typing at a SERS by hand (pyserial's miniterm) in a real terminal,
against `devsim run sers --link`: the drive's Latin-1 answers (`°`, `ß`) show as themselves."""

from __future__ import annotations

import re
import shlex
import sys
from pathlib import Path

from tests.support.programs import needs_program

from .run import ROOT, Proc
from .tmux import screen_until, terminal, tmux

_MINITERM = re.compile(r"`python -m serial\.tools\.miniterm ([^`]*)`")


def _miniterm_args(page: Path) -> list[str]:
    """The options of the miniterm command ``page`` shows (its port and baud rate dropped)."""
    found = _MINITERM.findall(page.read_text(encoding="utf-8"))
    assert found, f"{page.name} shows no miniterm command"
    (args,) = {tuple(shlex.split(text)[:-2]) for text in found}  # every one the same
    return list(args)


def test_the_readme_s_miniterm_command_shows_latin1_answers(tmp_path: Path) -> None:
    needs_program("tmux")
    options = _miniterm_args(ROOT / "README.md")
    assert options == _miniterm_args(ROOT / "docs" / "connect.md") == _miniterm_args(ROOT / "docs" / "kinds" / "sers.md")
    link = tmp_path / "ttySERS"
    sim = Proc("run", "sers", "--link", str(link))
    try:
        sim.expect(lambda line: line.startswith("sers: ready"), timeout=20)
        for shown, wanted in ((options, True), ([o for o in options if o not in ("--encoding", "latin1")], False)):
            with terminal([sys.executable, "-m", "serial.tools.miniterm", *shown, str(link), "9600"]) as session:
                screen_until(session, "Quit: Ctrl+]")
                for line in ("#P76=2", "#P51?", "#V=9999999"):  # degrees; a value too large
                    tmux("send-keys", "-t", session, "-l", line)
                    tmux("send-keys", "-t", session, "Enter")
                screen = screen_until(session, "zu gro")
                if wanted:
                    assert "P51=0°" in screen and "*V zu groß" in screen and "�" not in screen, screen
                else:  # what a user sees without --encoding latin1: why the README says it
                    assert "P51=0�" in screen, screen
    finally:
        sim.stop()
