"""An axis's register block as the kind's parameters part (spec pcd4h3.md §4.1, §4.2; manual
§7.1.5): the 20 registers live in the PCD's register medium from BAR + RAi, where a host reads
and writes them over S-Bus; :class:`AxisRegisters` is the library's named view of them
(``registers.destination`` for ``R DestP+RAi``).
"""

from __future__ import annotations

from collections.abc import Iterator, MutableMapping

from devsim.core.parameters import Key, Parameters, accessor
from devsim.core.words import signed32
from devsim.devices.pcd4h3.tables import REGISTERS
from devsim.devices.pcd4h3.units import ffp_encode

__all__ = ["AxisRegisters", "RegisterBlock"]

_KEYS: dict[str, Key] = {}  # register names (as spelled) → offsets, a memo of REGISTERS.lookup


class RegisterBlock(MutableMapping[Key, int]):
    """The block of one axis in the register medium, by offset: offset n is register
    ``base + n`` (§4.1); a register never written reads 0."""

    def __init__(self, medium: MutableMapping[int, int], base: int) -> None:
        self.medium, self.base = medium, base

    def _address(self, offset: Key) -> int:
        if not isinstance(offset, int) or offset not in REGISTERS:
            raise KeyError(offset)
        return self.base + offset

    def __getitem__(self, offset: Key) -> int:
        return self.medium.get(self._address(offset), 0)

    def __setitem__(self, offset: Key, value: int) -> None:
        self.medium[self._address(offset)] = value

    def __delitem__(self, offset: Key) -> None:
        self.medium.pop(self._address(offset), None)

    def __iter__(self) -> Iterator[Key]:
        return iter(REGISTERS.rows)

    def __len__(self) -> int:
        return len(REGISTERS)


class AxisRegisters(Parameters):
    """The register block of axis n (§4.2) with one accessor per register the library reads or
    writes.  Values are 32-bit PCD registers as stored (MCFac as its FFP pattern)."""

    proportional = accessor(0, "KProp")
    integral = accessor(1, "KInt")
    derivative = accessor(2, "KDer")
    integration_limit = accessor(3, "IntL")
    sample_interval = accessor(4, "SampI")
    machine_factor = accessor(5, "MCFac: the machine factor's FFP pattern")
    position_error_limit = accessor(6, "PosEr")
    destination = accessor(7, "DestP")
    break_position = accessor(8, "BrkP")
    velocity = accessor(9, "Veloc")
    acceleration = accessor(10, "Accel")
    status_reset = accessor(11, "StaFRR")
    control_word = accessor(12, "MCW")
    actual_position = accessor(13, "RActP")
    set_position = accessor(14, "RSetP")
    actual_velocity = accessor(15, "RActV")
    set_velocity = accessor(16, "RSetV")
    index_position = accessor(17, "RIndP")
    integration_sum = accessor(18, "RIntTS")
    signal_register = accessor(19, "RSigB")

    def __init__(self, block: RegisterBlock) -> None:
        super().__init__(REGISTERS, store=block)

    def named(self, symbol: str) -> int:
        """The register ``symbol`` (a configured display value, §3.4 DP14)."""
        key = _KEYS.get(symbol)
        if key is None:  # (the display asks every PLC cycle: a name is looked up once)
            key = _KEYS[symbol] = REGISTERS.lookup(symbol, "the register block").key
        return self.values[key]

    def load(self, symbol: str, value: float) -> None:
        """``LD R symbol+RAi value`` from the configuration: MCFac as a number (stored as its
        FFP pattern, §4.6), the others as whole numbers."""
        row = REGISTERS.lookup(symbol, "the register block")
        self.values[row.key] = signed32(ffp_encode(value)) if row.unit == "FFP" else signed32(int(value))
