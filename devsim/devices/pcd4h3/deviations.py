"""Where the pcd4h3 simulator knowingly differs from its manual, and why (``devsim doc pcd4h3``
prints these rows as the *Deviations* section of docs/devices/pcd4h3.md)."""

from __future__ import annotations

from devsim.core.kit import Deviation

DEVIATIONS: tuple[Deviation, ...] = ()
