"""The ``devsim`` command line (the top layer: it parses options and calls the rest).

* :mod:`devsim.cli.main` – the ``devsim`` group: ``list``, ``run``, ``doc``, and the lazily
  imported commands of the other modules;
* :mod:`devsim.cli.ctl` – ``devsim ctl``, one command per control op;
* :mod:`devsim.cli.present` – what ``devsim ctl`` prints: text for people, ``--json`` for scripts;
* :mod:`devsim.cli.exits` – the exit statuses every command shares (docs/cli.md);
* :mod:`devsim.cli.options` – checks of the facade and fleet options ``run`` and ``up`` share;
* :mod:`devsim.cli.docgen` – the Markdown of ``devsim doc``;
* :mod:`devsim.cli.replay` – ``devsim record`` and ``devsim replay``;
* :mod:`devsim.cli.monitor` – ``devsim monitor``;
* :mod:`devsim.cli.running` – ``devsim ps``, and which running simulator ``ctl`` and ``monitor`` mean;
* :mod:`devsim.cli.scenario` – ``devsim check``, ``devsim scenario run`` and ``devsim up``;
* :mod:`devsim.cli.plot` – ``devsim plot`` (the drawing is :mod:`devsim.observe.plot`);
* :mod:`devsim.cli.wireshark` – ``devsim wireshark --install`` and ``devsim extcap``.
"""

from devsim.cli.main import cli, main

__all__ = ["cli", "main"]
