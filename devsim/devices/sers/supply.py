"""The SERS's supervision of its supply, heat sink and power stage (manual §2.1.4, §3.5; spec
§2.7, §5.14).

Below U_W of the supply class a warning (it clears itself), below U_B a drive error after
braking (with P1058 the position is saved first), below U_L torque off at once; without option U
the logic itself goes off below U_L / 2 and comes back with the supply.  The heat sink warns at
75 °C and is an error at 85 °C; a short circuit switches off at once.
"""

from __future__ import annotations

from collections.abc import Callable

from devsim.core.signals import SignalBank
from devsim.devices.sers.constants import LIMIT, OVERTEMP, UNDERVOLTAGE
from devsim.devices.sers.memory import ParameterMemory
from devsim.devices.sers.power import PowerStage

__all__ = ["SupplyMonitor"]


class SupplyMonitor:
    """Supply voltage, heat-sink temperature, short circuit and the limit switches at power-on
    (§2.1.4, §3.5, §2.1.2)."""

    def __init__(
        self,
        signals: SignalBank,
        power: PowerStage,
        memory: ParameterMemory,
        thresholds: tuple[int, int, int, int],
        *,
        has_option_u: Callable[[], bool],
        alive: Callable[[], bool],
        logic_power: Callable[[bool], None],
    ) -> None:
        self.signals = signals
        self.power = power
        self.memory = memory
        self.thresholds = thresholds  # U_V max, U_W, U_B, U_L (§2.1.4)
        self._has_option_u = has_option_u
        self._alive = alive
        self._logic_power = logic_power

    def check_all(self) -> None:
        self.check_supply()
        self.check_temperature()
        self.check_short()

    def recheck(self) -> None:
        """``P12=0``: the supply and temperature warnings whose causes remain come back."""
        self.check_supply()
        self.check_temperature()

    def check_supply(self) -> None:
        """§2.1.4: U_W pre-warning (auto-clear), U_B error after braking, U_L torque off."""
        volts = float(self.signals.get("supply_voltage"))
        _u_max, u_w, u_b, u_l = self.thresholds
        power = self.power
        if not self._has_option_u() and volts < u_l / 2:
            if self._alive():
                self._logic_power(False)
            return
        if not self._alive():
            self._logic_power(True)
            return
        if volts < u_l:
            power.drive_error(UNDERVOLTAGE, immediate=True)
        elif volts < u_b:
            if not power.errors & UNDERVOLTAGE and self.memory.params.save_position_on_undervoltage:
                self.memory.possave()
            power.drive_error(UNDERVOLTAGE)
        if volts < u_w:
            power.warn(4)
        else:
            power.clear_warning(4)

    def check_temperature(self) -> None:
        """§3.5: warning at 75 °C (auto-clear), error at 85 °C."""
        celsius = float(self.signals.get("heatsink_temperature"))
        if not self._alive():
            return
        if celsius >= 85:
            self.power.drive_error(OVERTEMP)
        if celsius >= 75:
            self.power.warn(2)
        else:
            self.power.clear_warning(2)

    def check_short(self) -> None:
        if self._alive() and self.signals.get("short_circuit"):
            self.power.short_circuit()

    def check_limits_at_power_on(self) -> None:
        if self.signals.get("limit_left") or self.signals.get("limit_right"):
            self.power.errors |= LIMIT
