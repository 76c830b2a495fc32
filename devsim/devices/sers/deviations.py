"""Where the sers simulator knowingly differs from its manual, and why (``devsim doc sers``
prints these rows as the *Deviations* section of docs/devices/sers.md)."""

from __future__ import annotations

from devsim.core.kit import Deviation

DEVIATIONS: tuple[Deviation, ...] = ()
