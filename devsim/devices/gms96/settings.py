"""N parameters and the queued settings of the GMS96 card (manual §2.3.1 N, B, M, S, f, G, O,
o, d, r; spec §3.8, §4.6, §5.9)."""

from __future__ import annotations

from typing import Any

from devsim.devices.gms96 import tables
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

    def defaults(self) -> None:
        """``r0``: the defaults of the position controller and the indexer (manual §2.3.1 r)."""
        self.params.defaults()
        self.M, self.B, self.S = tables.DEFAULTS["M"], tables.DEFAULTS["B"], tables.DEFAULTS["S"]
        self.override_on = bool(tables.DEFAULTS["override_active"])
