"""N parameters and the queued settings of the GMS96 card (manual §2.3.1 N, B, M, S, f, G, O,
o, d, r; spec §3.8, §4.6, §5.9)."""

from __future__ import annotations

from typing import Any

from devsim.devices.gms96 import tables
from devsim.devices.gms96.executor import Cmd
from devsim.devices.gms96.params import NParameters

__all__ = ["Settings"]


class Settings:
    """Part of :class:`~devsim.devices.gms96.card.Gms96Card`: writing N parameters and the
    settings the executor hands back in queue order."""

    params: NParameters
    cfg: Any
    indexer: Any
    image: Any
    axis: Any
    nvram: Any

    def set_n(self, index: int, value: int, p3: int = 0) -> None:
        """``N value;index;P3`` (manual §2.3.1 N) and the ``param.N*`` points."""
        if not self.params.write(index, value, p3):
            return
        if index in (10, 20, 27, 28):
            self.indexer.arm_following_error()
        if index in (15, 39):
            self._i2t_update()
        self.changed()

    # -- queued settings the executor hands back (B, M, f, G, O, o, S, d, r) ------------------------
    def queued_setting(self, cmd: Cmd) -> bool:
        letter, p1, p2, p3 = cmd.letter, cmd.p1, cmd.p2, cmd.p3
        if letter == "B":
            self.B = tables.clamp_setting("B", p1)
        elif letter == "M":
            self.M = tables.clamp_setting("M", p1)
        elif letter == "S":
            self.S = tables.clamp_setting("S", p1)
        elif letter == "f":
            self.f = max(1, min(p1, tables.RANGES["f"][1]))
            self.f_frac = max(0, min(255, p2))
        elif letter == "G":
            self._g(p1, p2, p3)
        elif letter == "O":
            value = max(tables.POSITION_MIN, min(tables.POSITION_MAX, p1))
            self.origin = self.axis.position() - value - self.offsets()
        elif letter == "o":
            if p1 in (0, 1):
                self.override_on = bool(p1)
        elif letter == "d":
            if 0 <= p2 <= 254:
                self.image.write_word(p2, p1)
                if p2 < 160:
                    self.save_static()
        elif letter == "r":
            if p3 == 0:
                self._defaults()
            elif p3 == 1:
                self.nvram.delete("eeprom")
        self.indexer.replan()
        self.changed()
        return True

    def _defaults(self) -> None:
        self.params.defaults()
        self.M, self.B, self.S = tables.DEFAULTS["M"], tables.DEFAULTS["B"], tables.DEFAULTS["S"]
        self.override_on = bool(tables.DEFAULTS["override_active"])

    def _g(self, p1: int, p2: int, p3: int) -> None:
        """G functions (manual §2.3.1 G; spec §3.8.6, §5.9)."""
        zp = None
        if p1 & 0xFF == 54 and 0 < (p1 >> 8) & 0xFF <= 15:
            zp = 54 + ((p1 >> 8) & 0xFF)
        elif 54 <= p1 <= 57:
            zp = p1
        if p1 == 0:
            self.f = self.M
        elif p1 == 53:
            if p3 == 1:
                self.machine_zero = p2
                self.save_offsets()
            else:
                self._before_g53 = (self.active_zero, self.tool_active)
                self.active_zero = None
                if p2 == 1:
                    self.tool_active = False
        elif zp is not None:
            if p3 == 1:
                self.zero_table[zp] = p2
                self.save_offsets()
            elif p2 == 1:
                self.active_zero, self.tool_active = self._before_g53
            else:
                self.active_zero = zp
        elif p1 == 90:
            self.g_relative = False
        elif p1 == 91:
            self.g_relative = True
        elif p1 == 92:
            self.g92 = p2
        elif p1 in (94, 95):
            self.feed_mode = p1
