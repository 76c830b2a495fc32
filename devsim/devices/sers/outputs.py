"""What the SERS shows: the ready relay, the outputs that follow its state (P1125, P1126, P1131,
P1132, the brake P1036) and the 7-segment display (manual §2.1.3, §3.5, §4.8.1.2; spec §4.7).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from devsim.core.signals import SignalBank
from devsim.devices.sers.constants import ERROR_DISPLAY, SHORT, WARNING_DISPLAY
from devsim.devices.sers.memory import ParameterMemory
from devsim.devices.sers.params import SersParameters
from devsim.devices.sers.power import PowerStage

__all__ = ["Outputs"]


class Outputs:
    """The ready relay, the state outputs and the display of one SERS (§2.1.3, §3.5, §4.8.1.2)."""

    def __init__(
        self,
        signals: SignalBank,
        params: SersParameters,
        power: PowerStage,
        memory: ParameterMemory,
        *,
        alive: Callable[[], bool],
        booting: Callable[[], bool],
        in_position: Callable[[], bool],
        program_running: Callable[[], bool],
    ) -> None:
        self.signals = signals
        self.params = params
        self.power = power
        self.memory = memory
        self._alive = alive
        self._booting = booting
        self._in_position = in_position
        self._program_running = program_running

    def update(self) -> None:
        """The relay and the outputs assigned to a state follow it (a negative selector: the
        output shows the inverse)."""
        if not self._alive():
            return
        power, signals = self.power, self.signals
        signals.set("READY", bool(power.relay))  # (a drive error opens it after braking, §2.1.3)
        in_position, running, error, warning, brake = self.params.output_selectors()
        if in_position or running or error or warning:  # (none assigned, the factory setting: nothing to do)
            for selected, state in (
                (in_position, self._in_position),
                (running, self._program_running),
                (error, power.has_errors),
                (warning, power.has_warnings),
            ):
                sel = int(selected)
                if sel and abs(sel) <= 4:
                    on = state()
                    signals.set(f"O{abs(sel)}", on if sel > 0 else not on)
        brake = int(brake)
        if brake:
            off = not power.energized
            signals.set(f"O{abs(brake)}", off if brake > 0 else not off)

    def display(self) -> dict[str, Any]:
        """7-segment display (§3.5, spec §4.7 priority)."""
        if not self._alive():
            return {"char": " ", "blinking": False}
        if self._booting():
            return {"char": "-", "blinking": False}
        power = self.power
        if power.errors & SHORT:
            return {"char": "E", "blinking": False}
        if self.memory.eeprom_checksum_error:
            return {"char": "7", "blinking": False}
        for bit, char in ERROR_DISPLAY:
            if power.errors & bit:
                return {"char": char, "blinking": False}
        for bit, char in WARNING_DISPLAY:
            if power.warnings & bit:
                return {"char": char, "blinking": True}
        if power.energized:
            return {"char": "5", "blinking": bool(self.signals.get("stop"))}
        return {"char": "4", "blinking": False}
