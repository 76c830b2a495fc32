"""The screen's message line and the events the control reports (manual §2.3.4, §2.4.4, §2.6:
``WERTBEREICHES-UEBERLAUF``, ``LIMIT_SWITCH``, ``OUTSIDE_WORKING_FIELD``; spec poselesta.md §4.10).

Every part that shows a message or reports an event does it here: the message is what
``panel.message`` reads, an event is noted for timing checks and announced on the model's
topic ``event`` as ``(kind, what, detail)``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

__all__ = ["Screen"]


class Screen:
    """The message line of the control's screen and its event reports (manual §2.6; spec §4.10)."""

    def __init__(self, record: Callable[[str], None], announce: Callable[..., None]) -> None:
        self._record = record
        self._announce = announce
        self.message = ""

    def show(self, message: str) -> None:
        self.message = message

    def clear(self) -> None:
        self.message = ""

    def record(self, name: str) -> None:
        """Note a moment (``limit_switch``, ``position_reached`` …) in the model's event log."""
        self._record(name)

    def report(self, kind: str, what: str, detail: Any = None) -> None:
        """Announce ``(kind, what, detail)`` on the topic ``event`` (a host developer's view)."""
        self._announce("event", kind, what, detail)

    def port_event(self, port: str, what: str, detail: Any = None) -> None:
        """An event of a port (``v6.block``, ``v8.key`` …): noted and announced."""
        self._record(f"{port}.{what}")
        self._announce("event", port, what, detail)
