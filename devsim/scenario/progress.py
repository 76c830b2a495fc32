"""Progress of ``devsim scenario run`` on stderr (stdout keeps the reports).

A real-time scenario prints each step as it happens (the report's line for it).  On a terminal a
bar below the steps shows how far the run is through the timeline (the time its ``at``,
``after`` and ``wait`` steps add up to; by steps where it has none), redrawn a few times a
second, and with several files which file of how many.  Without a terminal there is no bar:
the step lines, and ``[2/5] FILE`` before each file of a run over several.
"""

from __future__ import annotations

import os
import sys
import threading
import time
from typing import Any, TextIO

from devsim.scenario.published import timeline_length
from devsim.scenario.report import format_step
from devsim.scenario.runner import StepResult
from devsim.scenario.schema import Scenario

__all__ = ["Progress", "timeline_length"]

_WIDTH = 30  # characters of the bar
_REDRAW = 0.2  # seconds between redraws on a terminal


class Progress:
    """Shows the run of ``files`` scenario files on ``stream`` (a terminal or not)."""

    def __init__(self, files: int, stream: TextIO | None = None, tty: bool | None = None) -> None:
        # (a process started with stderr closed, `2>&-`, has none: the progress goes nowhere)
        self.stream = stream if stream is not None else sys.stderr or open(os.devnull, "w")  # noqa: SIM115
        self.tty = self.stream.isatty() if tty is None else tty
        self.files = files
        self.index = 0
        self._lock = threading.Lock()
        self._out = threading.Lock()
        self._steps = 0
        self._done = 0
        self._end = 0.0
        self._speed = 1.0
        self._at: tuple[float, float] | None = None  # (timeline time, monotonic) of the last step
        self._stop = threading.Event()
        self._ticker: threading.Thread | None = None

    # -- one file -------------------------------------------------------------------------------
    def begin(self, path: str, scenario: Scenario, *, realtime: bool, speed: float = 1.0) -> None:
        """A file starts (``realtime``: its steps are shown as they happen)."""
        self.index += 1
        self._steps = len(scenario.steps)
        self._done = 0
        self._end = timeline_length(scenario)
        self._speed = speed
        self._at = None
        if not self.tty:
            if self.files > 1:
                self._write(f"[{self.index}/{self.files}] {path}\n")
            return
        if not realtime:
            self._redraw()
            return
        self._stop.clear()
        self._ticker = threading.Thread(target=self._tick, name="devsim-progress", daemon=True)
        self._ticker.start()

    def step(self, step: StepResult | None, now: float) -> None:
        """The runner's hook (loop thread): ``step`` finished at timeline time ``now``."""
        with self._lock:
            self._at = (now, time.monotonic())
            if step is None:  # the timeline starts (the plant's ports are printed by then)
                text = ""
            else:
                self._done += 1
                text = "\n".join(format_step(step)) + "\n"
        if self.tty:
            self._write("\r\x1b[K" + text)
            self._redraw()
        elif text:
            self._write(text)

    def end(self) -> None:
        """The file has finished: the bar goes (its report follows on stdout)."""
        if self._ticker is not None:
            self._stop.set()
            self._ticker.join(5)
            self._ticker = None
        if self.tty:
            self._write("\r\x1b[K")

    # -- drawing --------------------------------------------------------------------------------
    def _tick(self) -> None:
        while not self._stop.wait(_REDRAW):
            if self._at is not None:  # not before the timeline starts
                self._redraw()

    def _now(self) -> float:
        if self._at is None:
            return 0.0
        at, wall = self._at
        return at + (time.monotonic() - wall) * self._speed

    def bar(self) -> str:
        """The bar line as it would be drawn now."""
        with self._lock:
            now = self._now()
            fraction = min(1.0, now / self._end) if self._end > 0 else (
                self._done / self._steps if self._steps else 1.0)
            if self._done >= self._steps:
                fraction = 1.0
            filled = round(fraction * _WIDTH)
            text = f"[{'#' * filled}{'.' * (_WIDTH - filled)}] {now:7.2f}"
            text += f"/{self._end:.2f} s" if self._end > 0 else " s"
            text += f"  step {self._done}/{self._steps}"
            if self.files > 1:
                text += f"  file {self.index}/{self.files}"
        return text

    def _redraw(self) -> None:
        self._write("\r\x1b[K" + self.bar())

    def _write(self, text: Any) -> None:
        with self._out:
            try:
                self.stream.write(text)
                self.stream.flush()
            except (OSError, ValueError):
                pass  # stderr gone: progress is not worth failing a run
