"""Record and replay: ``devsim record`` between a host and a device, ``devsim replay`` of the
device side, with a hand-over to the live model of the kind.

* :mod:`devsim.observe.replay.session` – the session file (JSON lines: a header, then one line per
  chunk with time, direction, bytes and the kind's decoding) and how it is cut into exchanges.
* framing, decoding and match tolerances: what each kind declares on its port
  (:attr:`devsim.core.kit.PortDef.framing`, e.g. :mod:`devsim.devices.gms96.framing`).
* :mod:`devsim.observe.replay.recorder` – the recording proxy.
* :mod:`devsim.observe.replay.player` – the replaying device, its matching and the live fallback.
* :mod:`devsim.cli.replay` – the two commands.
"""
