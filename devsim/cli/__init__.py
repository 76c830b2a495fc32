"""The ``devsim`` command line (the top layer: it parses options and calls the rest).

* :mod:`devsim.cli.quick` – the entry point (:func:`main`): a plain ``devsim run`` command line
  served without click, anything else handed to click;
* :mod:`devsim.cli.main` – the ``devsim`` group (:data:`cli`): ``list``, ``run``, ``doc``, and the
  lazily imported commands of the other modules;
* :mod:`devsim.cli.serve` – ``devsim run``'s plan and server, without click;
* :mod:`devsim.cli.ctl` – ``devsim ctl``, one command per control op;
* :mod:`devsim.cli.present` – what ``devsim ctl`` prints: text for people, ``--json`` for scripts;
* :mod:`devsim.cli.exits` – the exit statuses every command shares (docs/cli.md), their numbers in
  :mod:`devsim.cli.statuses` (without click);
* :mod:`devsim.cli.options` – checks of the facade and fleet options ``run`` and ``up`` share;
* :mod:`devsim.cli.docgen` – the Markdown of ``devsim doc``;
* :mod:`devsim.cli.replay` – ``devsim record`` and ``devsim replay``;
* :mod:`devsim.cli.monitor` – ``devsim monitor``;
* :mod:`devsim.cli.running` – ``devsim ps``, and which running simulator ``ctl`` and ``monitor`` mean;
* :mod:`devsim.cli.scenario` – ``devsim check``, ``devsim scenario run`` and ``devsim up``;
* :mod:`devsim.cli.plot` – ``devsim plot`` (the drawing is :mod:`devsim.observe.plot`);
* :mod:`devsim.cli.wireshark` – ``devsim wireshark --install`` and ``devsim extcap``.
"""

from __future__ import annotations

from typing import Any

from devsim.cli.quick import main

__all__ = ["cli", "main"]


def __getattr__(name: str) -> Any:
    """``cli``, the click group, imported when asked for (``devsim run`` starts without click)."""
    if name == "cli":
        from devsim.cli.main import cli

        return cli
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
