"""Looking at a running plant, above the runtime and the facades, below scenarios and the CLI:

* :mod:`devsim.observe.motion_log` – axis positions and events as CSV while a plant runs;
* :mod:`devsim.observe.plot_data` and :mod:`devsim.observe.plot` – pictures of motion logs and
  wire traces (``devsim plot``);
* :mod:`devsim.observe.live_log` – what happens, one line each on stderr (``devsim run``/``up``);
* :mod:`devsim.observe.monitor` – the terminal UI of ``devsim monitor`` (textual);
* :mod:`devsim.observe.replay` – record a host's session with a device and replay it.

What a port's bytes mean comes from the framing the kind declares on it
(:attr:`devsim.core.kit.PortDef.framing`); nothing here names a kind.
"""
