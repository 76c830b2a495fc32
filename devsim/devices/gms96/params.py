"""The card's N parameters as a part: values, N8's pair and the card's range rule (manual §2.3.1 N,
r, s, T; spec §3.8.10, §4.6).

The rows are :data:`~devsim.devices.gms96.nparams.N_TABLE`; the model reads the values through
the accessors below (``params.following_error_limit``), a face that addresses a parameter by the
number the host sent uses :meth:`NParameters.read` / :meth:`NParameters.write`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from devsim.core.nvram import numbered
from devsim.core.parameters import Parameters, accessor
from devsim.devices.gms96.nparams import N_TABLE, n_range
from devsim.devices.gms96.tables import clamp_n

__all__ = ["NParameters"]


class NParameters(Parameters):
    """The N parameters of one card (manual §2.3.1 N).

    N8 holds two values, selected by P3 (0 = lower, 1 = upper limit of the home-position window):
    :attr:`n8`.  A write out of a parameter's range is clamped (``out_of_range: clamp``, spec
    §3.8.10) or ignored (``ignore``); N34/N35 are coupled (N34 >= 1.5·N35), N10 has the stepper
    range on a stepper card."""

    position_gain = accessor(10, "N10: position controller P gain (Kv = kv_per_n10 · N10)")
    i2t_level = accessor(15, "N15: I²t current limit in 1/255 of Imax")
    motion_disabled = accessor(17, "N17: 1 = moves run in time only (M3.4)")
    reference_type = accessor(19, "N19: the Q P1 (LSB) and P2 (middle byte) of Q-1")
    following_error_limit = accessor(20, "N20: the permissible following error [inc]")
    brake_output = accessor(21, "N21: 1 = A0.0 is the brake output (from the next start)")
    motor_inverted = accessor(22, "N22: 1 = motor direction inverted")
    counter_weight = accessor(23, "N23: set-point increments per counter-input increment")
    ramp_type = accessor(24, "N24: 0 = linear, 1 = sin² ramps")
    in_position_window = accessor(27, "N27: in-position window [inc] (> 0: A0.1 shows it)")
    in_position_time_ms = accessor(28, "N28: in-position time [ms]")
    drive_off_position = accessor(33, "N33: drive-off position of Q-1 [inc]")
    peak_current_pct = accessor(39, "N39: peak current in % of the hardware maximum")
    backlash = accessor(41, "N41: backlash compensation amount [inc]")
    backlash_speed = accessor(42, "N42: backlash compensation speed [inc/ms]")
    binary_options = accessor(50, "N50: binary options (bit 0: actual value from the counter input)")
    enable_input = accessor(51, "N51: 1 = E0.0 is the indexer enable")

    def __init__(self, *, factory: Mapping[int, int], stepper: bool, out_of_range: str) -> None:
        super().__init__(N_TABLE)
        #: The configured factory values (``params:``), clamped to their ranges at power-on.
        self.factory = dict(factory)
        self.stepper = stepper
        self.out_of_range = out_of_range
        #: N8: [lower, upper] limit of the home-position window.
        self.n8: list[int] = [self.values[8], 0]

    def power_on(self, eeprom: Mapping[str, Any] | None) -> None:
        """The factory values, the configured ones, then what ``s85;170`` saved (manual §2.3.1 s)."""
        self.reset()
        for index, value in self.factory.items():
            if index in self.table:
                self.values[index] = clamp_n(index, value)
        self.n8 = [self.values[8], 0]
        if eeprom:
            # what s85;170 saved is in range; a hand-edited value is clamped as a write is (spec
            # §3.8.10), one that is no whole number refuses the memory (UnfitMemory at the start);
            # before, N8 "ab" or [1.5, "x"] loaded as it was and failed every read of N8.  A key is
            # the number as s85;170 writes it (str(n)), else the memory is refused: int() took
            # '٣٩', '+39', ' 39', '039' and '3_9' for N39 (a second N39 beside "39").
            # [SIM-CHOICE] A number no N parameter has is ignored, as before.
            # s85;170 writes every N parameter and both limits of N8 (an empty N or N8, or null,
            # read as none saved before)
            stored = numbered(eeprom["N"], "N parameter")
            if not stored or type(eeprom["N8"]) is not list or len(eeprom["N8"]) != 2:
                raise ValueError(f"stored N parameters {eeprom['N']!r:.30} and N8 {eeprom['N8']!r:.30} are not"
                                 " what s85;170 writes")
            for index, value in stored.items():
                if index in self.table:
                    self.values[index] = clamp_n(index, _whole(value), stepper=self.stepper)
            lower, upper = eeprom["N8"]
            self.n8 = [clamp_n(8, _whole(lower)), clamp_n(8, _whole(upper))]

    def defaults(self) -> None:
        """``r`` P3 = 0: the "Grundstellung" (the factory values, not the configured ones)."""
        self.reset()
        self.n8 = [self.values[8], 0]

    def eeprom(self) -> dict[str, Any]:
        """What ``s85;170`` saves of the N parameters."""
        return {"N": {str(k): v for k, v in self.values.items()}, "N8": list(self.n8)}

    def read(self, index: int, p3: int = 0) -> int:
        """``T5;index;P3``: a parameter's value (N8: P3 = 1 the upper limit)."""
        if index == 8:
            return self.n8[1 if p3 == 1 else 0]
        return int(self.values.get(index, 0))

    def write(self, index: int, value: int, p3: int = 0) -> bool:
        """``N value;index;P3``: store ``value`` clamped to the range (spec §3.8.10); False if the
        card ignores it (no such parameter, or out of range with ``out_of_range: ignore``)."""
        row = self.table.get(index)
        if row is None:
            return False
        lo, hi = n_range(row)
        if self.out_of_range == "ignore" and not lo <= value <= hi:
            return False
        value = clamp_n(index, value, self.values, stepper=self.stepper)
        if index == 8:  # the window's limits act nowhere in the simulator: no listener
            self.n8[1 if p3 == 1 else 0] = value
            if p3 != 1:
                self.values[8] = value
        else:
            self.set(index, value, check=False)  # the parts that listen act on it
        return True


def _whole(value: Any) -> int:
    """A stored N value: a JSON integer (not a bool, a string, a fraction)."""
    if type(value) is not int:
        raise ValueError(f"N parameter value {value!r} is no whole number")
    return value
