"""Where the gms96 simulator knowingly differs from its manual, and why (``devsim doc gms96``
prints these rows as the *Deviations* section of docs/devices/gms96.md)."""

from __future__ import annotations

from devsim.core.kit import Deviation

DEVIATIONS: tuple[Deviation, ...] = ()
