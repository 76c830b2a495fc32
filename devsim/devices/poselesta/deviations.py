"""Where the poselesta simulator knowingly differs from its manual, and why (``devsim doc poselesta``
prints these rows as the *Deviations* section of docs/devices/poselesta.md)."""

from __future__ import annotations

from devsim.core.kit import Deviation

DEVIATIONS: tuple[Deviation, ...] = ()
