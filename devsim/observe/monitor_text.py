"""What the live monitor (:mod:`devsim.observe.monitor`) writes in words: a device's display as
its front shows it, and the clock line of the header.  Pure, no textual.

A display is every watched point named ``display`` or ``….display`` and the screen message
(``panel.message``), whatever the kind: a SERS's 7-segment character (``{"char", "blinking"}``),
a PCD4.H3 axis's PCA2.D14 lines (``[top, bottom]``, DP14's digits), a POSELESTA axis's actual value
(a string) and its screen message.  Each value is shown by its shape, a table of callables.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from typing import Any

__all__ = ["LINE_FAULTS", "clock_line", "display_line", "is_display", "message_line", "shown_display"]

#: The last part of a point name that makes it a display (``display``, ``axis.1.display``,
#: ``panel.message``).
DISPLAY_NAMES = ("display", "message")
#: Line faults the monitor's menu and the web page offer, with the parameters they need.
LINE_FAULTS: dict[str, dict[str, Any]] = {
    "unplug": {}, "hang": {}, "silent": {}, "noise": {"rate": 50}, "baud_mismatch": {"baudrate": 4800},
    "corrupt": {}, "drop": {}, "delay": {"delay": 0.2},
}


def is_display(name: str) -> bool:
    """Whether the point ``name`` is something the device's front shows."""
    return name.rsplit(".", 1)[-1] in DISPLAY_NAMES


def _segment(value: dict[str, Any]) -> str:
    """A 7-segment digit: its character, and that it blinks."""
    char = str(value.get("char", ""))
    shown = repr(char) if not char.strip() else char  # a dark display shows as ' '
    return f"{shown} blinking" if value.get("blinking") else shown


def _lines(value: list[Any]) -> str:
    """The lines of an LCD or digit display, each kept as wide as the device shows it."""
    return "[" + " / ".join(str(line) for line in value) + "]"


def _text(value: str) -> str:
    return value


#: Value shape → its text; anything else is shown as it came.
_SHAPES: dict[type, Callable[[Any], str]] = {dict: _segment, list: _lines, str: _text}


def shown_display(value: Any) -> str:
    """One display's value as its front shows it (``9 blinking``, ``[  1234 /      0]``, ``12.500``)."""
    for shape, show in _SHAPES.items():
        if isinstance(value, shape):
            return show(value)
    return "-" if value is None else str(value)


def display_line(values: Mapping[str, Any]) -> str:
    """Every display of a device in one line: ``9 blinking``, ``axis.1 [  1234 /      0]``,
    ``axis.x 12.500  axis.y 0.000``; "" when there is none."""
    parts = []
    for name, value in values.items():
        if name.rsplit(".", 1)[-1] == "display" and value is not None:
            # the device's own display shows bare, an axis's after the axis
            parts.append(f"{name.removesuffix('display').rstrip('.')} {shown_display(value)}".strip())
    return "  ".join(parts)


def message_line(values: Mapping[str, Any]) -> str:
    """The screen messages of a device (``panel.message``: ``WERTBEREICHES-UEBERLAUF``); "" when none shows."""
    return "  ".join(str(value) for name, value in values.items()
                     if name.rsplit(".", 1)[-1] == "message" and value not in ("", None))


def clock_line(device_time: float | None, *, stopped: bool = False, wall: float | None = None) -> str:
    """The header's clock: the device time (seconds) and the wall time, ``t = 12.000 s · 01:52:07``."""
    now = time.strftime("%H:%M:%S", time.localtime(time.time() if wall is None else wall))
    if stopped:
        return f"the simulator stopped · {now}"
    if device_time is None:
        return f"attaching · {now}"
    return f"t = {device_time:.3f} s · {now}"
