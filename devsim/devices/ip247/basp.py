"""The command output disable BASP from the S5 bus and the jumper X21 that decides what it does
to the IP247 (manual §2.9, §3.3; spec ip247.md §5.13).

With X21 2-3 (the default) BASP brakes every running axis (error 55 on all axes) and forces the
"position reached" outputs low; with X21 1-2 the module ignores it.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

__all__ = ["Basp"]


class Basp:
    """Whether BASP is active as the module sees it (manual §2.9)."""

    def __init__(self, config: Mapping[str, Any]) -> None:
        self._config = config
        self.active = False

    @property
    def honoured(self) -> bool:
        """X21 2-3: the module reacts to BASP (spec §5.13)."""
        return self._config.get("x21", "2-3") == "2-3"

    @property
    def forces_pe(self) -> bool:
        """PE is held low while BASP is active and honoured."""
        return self.active and self.honoured
