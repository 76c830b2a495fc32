"""The running process: one event loop, one clock, the devices and the ports they are served on
(:mod:`devsim.runtime.process`), the control API out of process (:mod:`devsim.runtime.control`)
and the stream of a device's changes and events it serves (:mod:`devsim.runtime.watch_stream`).

Above :mod:`devsim.core` and :mod:`devsim.transports`; it knows no kind (kinds come from
:mod:`devsim.core.registry`).
"""

from devsim.runtime.process import MAX_ADVANCE, Runtime, UnknownDevice, port_key

__all__ = ["MAX_ADVANCE", "Runtime", "UnknownDevice", "port_key"]
