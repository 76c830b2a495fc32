"""Where the ip247 simulator knowingly differs from its manual, and why (``devsim doc ip247``
prints these rows as the *Deviations* section of docs/devices/ip247.md)."""

from __future__ import annotations

from devsim.core.kit import Deviation

DEVIATIONS: tuple[Deviation, ...] = ()
