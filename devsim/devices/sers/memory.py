"""The SERS's parameter memory: the EEPROM image of the parameters, of R0..R5 and W, and of the
position (manual §4.8.6.10 PSAVE / P1004, §4.8.4.2 POSSAVE, §3.5 the checksum error; spec §4.1,
§4.8).

At power-on the RAM image is the factory values, the configured ones (``params:``), what PSAVE
stored (unless the EEPROM checksum is bad) and the power-on values of the parameters that are
never stored; the program lives in the same memory but is :class:`~.program.ProgramMemory`'s.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from typing import Any

from devsim.core.console import warn
from devsim.core.nvram import NonVolatileMemory, stored_key
from devsim.devices.sers.constants import WEIGHTED_KINDS, WEIGHTING_PARAMS
from devsim.devices.sers.paramdef import range_problem
from devsim.devices.sers.parameters import (
    CURRENT_MAX_MA,
    FACTORY_DEFAULTS,
    KIND,
    PARAMETER_TABLE,
    PARAMETERS,
    SAVED_WITH_P1117,
)
from devsim.devices.sers.params import SersParameters
from devsim.devices.sers.units import Scaling

__all__ = ["ParameterMemory"]

#: W and the registers R0..R5: stored by P1004=5, and by PSAVE with P1117=1.
REGISTERS = tuple(sorted(SAVED_WITH_P1117))


class ParameterMemory:
    """PSAVE, POSSAVE, P1004 and the power-on image of the parameters (§4.8.6.10, §4.8.4.2)."""

    def __init__(
        self,
        nvram: NonVolatileMemory,
        params: SersParameters,
        config: Callable[[], Any],
        position: Callable[[], float],
    ) -> None:
        self.nvram = nvram
        self.params = params
        self._config = config
        self._position = position  # P51 in increments (what POSSAVE stores)
        #: The EEPROM's checksum was bad at power-on (display '7'; cleared by PSAVE, P1004=3).
        self.eeprom_checksum_error = False

    def power_on(self) -> None:
        """§4.1 steps 3–4: the checksum, then the parameters from the EEPROM."""
        self.eeprom_checksum_error = self.nvram.corrupt
        ram = self._factory_image()
        stored = self.nvram.get("params")
        if "params" in self.nvram and not self.eeprom_checksum_error:
            # (PSAVE writes every saved parameter: null, {} or 0 read as no PSAVE before)
            problem = _unfit(stored) or (None if stored else "it holds no parameter PSAVE writes")
            if problem is not None:
                # [SIM-CHOICE] a stored value the drive never stores (a hand edit): the EEPROM
                # fails its checksum as a damaged one does (display '7', factory values); before,
                # the value went into RAM and failed later in a query, a motion or the line.
                warn(f"devsim: memory {self.nvram.path or 'memory'}: {problem}; the EEPROM reads as failing"
                     " its checksum (display 7, factory values)")
                self.eeprom_checksum_error = True
            else:
                for key, value in stored.items():
                    ram[int(key)] = value
        # not stored: power-on values (spec §4.1 step 4)
        ram.update({1110: 1, 1035: 1, 1: 0, 1047: 0, 1164: 0, 1165: 0, 1118: 0})
        for n in (100, 101, 102, 1101, 1102, 1103):
            ram[n] = 0
        # P1004=5 (or PSAVE with P1117=1) writes all seven, R0..R5 and W: one missing, null or {}
        # read as 0 before
        extra = self.nvram.get("registers", {})
        if "registers" in self.nvram and (type(extra) is not dict or sorted(extra) != sorted(map(str, REGISTERS))
                                          or not all(_finite(extra[str(n)]) for n in REGISTERS)):
            warn(f"devsim: memory {self.nvram.path or 'memory'}: R0..R5 and W are not the seven finite numbers"
                 " P1004=5 stores; the EEPROM reads as failing its checksum (display 7, registers 0)")  # [SIM-CHOICE] as above
            self.eeprom_checksum_error = True
            extra = {}
        for n in REGISTERS:
            ram[n] = extra.get(str(n), 0)
        self.params.load(ram)
        if "position" in self.nvram and not _finite(self.nvram.get("position")):
            # [SIM-CHOICE] as above: POSSAVE writes a number (before: P51 started at 0 without a word)
            warn(f"devsim: memory {self.nvram.path or 'memory'}: the position POSSAVE stored is no finite number;"
                 " the EEPROM reads as failing its checksum (display 7, P51 0)")
            self.eeprom_checksum_error = True

    def saved_position(self) -> float | None:
        """P51 as POSSAVE stored it (increments), or None (also for a stored value that is no
        finite number: P51 starts at 0 as without a POSSAVE)."""
        saved = self.nvram.get("position")
        return float(saved) if _finite(saved) else None

    def _factory_image(self) -> dict[int, Any]:
        """Factory defaults plus the configured EEPROM values, in internal units."""
        cfg = self._config()
        image: dict[int, Any] = dict(FACTORY_DEFAULTS)
        image[1010] = CURRENT_MAX_MA[cfg.current_class] // 2
        user: dict[int, Any] = {}
        for key, value in cfg.params.items():
            user[PARAMETER_TABLE.lookup(key).key] = value
        for number in WEIGHTING_PARAMS:
            if number in user:
                image[number] = user[number]
        scaling = Scaling(int(image[76]), int(image[44]), int(image[160]), image[121], image[122], image[123])
        for number in PARAMETERS:
            value = user.get(number, image.get(number))
            if value is None:
                continue
            kind = KIND[number]
            if kind in WEIGHTED_KINDS:
                value = scaling.to_internal(kind, float(value))
            image[number] = value
        return image

    def psave(self) -> None:
        """P1004=2: RAM parameters → EEPROM (W and R0..R5 only with P1117=1), in one write of
        the file: written one after the other, a kill between them left the new parameters with
        the registers of an earlier save, an EEPROM this PSAVE never wrote."""
        ram = self.params.values
        sections = {"params": {str(n): ram[n] for n, row in PARAMETERS.items() if row.saved and n in ram}}
        if self.params.save_registers_too:
            sections["registers"] = self._registers()
        self.nvram.put_sections(sections)
        self.eeprom_checksum_error = False

    def save_registers(self) -> None:
        """P1004=5: R0..R5 and W."""
        self.nvram.put("registers", self._registers())

    def _registers(self) -> dict[str, Any]:
        """R0..R5 and W as P1004=5 (or PSAVE with P1117=1) stores them."""
        ram = self.params.values
        return {str(n): ram[n] for n in REGISTERS}

    def factory_defaults(self) -> None:
        """P1004=3: EEPROM and RAM parameters back to factory defaults."""
        self.nvram.delete("params", "registers")  # (one write: a kill leaves both or neither)
        ram = self.params.values
        keep = {n: ram[n] for n in REGISTERS}
        ram.update(self._factory_image())
        ram.update(keep)
        self.eeprom_checksum_error = False

    def possave(self) -> None:
        """P1004=4: actual position P51 → EEPROM, restored at the next power-on."""
        self.nvram.put("position", self._position())


def _unfit(stored: Any) -> str | None:
    """What makes a stored parameter image one PSAVE never writes, or None: a number that is no
    saved parameter, a value that is no finite number, a fractional integer, or (unweighted, so
    kept in the unit its range is in) one outside its choices or range (:func:`~.paramdef.range_problem`)."""
    if type(stored) is not dict:
        return f"the parameters are a {type(stored).__name__}, not a table"
    for key, value in stored.items():
        try:  # (the number as PSAVE writes it, str(n): not '٤١', '+41' nor '041', a second P41)
            row = PARAMETERS.get(stored_key(key, "parameter"))
        except ValueError:
            row = None
        if row is None or not row.saved:
            return f"P{key} is no parameter PSAVE stores"
        if not _finite(value):
            return f"P{key}={value!r} is no finite number"
        kind = KIND[row.key]  # type: ignore[index]
        if kind == "int" and not float(value).is_integer():
            return f"P{key}={value!r} is no integer"
        if kind not in WEIGHTED_KINDS and (problem := range_problem(row, value)) is not None:
            return f"P{key}: {problem}"  # (the choices are on integer rows only, none weighted)
    return None


def _finite(value: Any) -> bool:
    """A JSON number a float holds, finite (not a bool, a string, null, nor an int beyond floats)."""
    return type(value) in (int, float) and value - value == 0 and -sys.float_info.max <= value <= sys.float_info.max
