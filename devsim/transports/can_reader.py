"""A python-can virtual bus read by a thread that sleeps until a frame comes and ends at once when
stopped (the CANopen facades' network and the socketcand server's sessions, :mod:`devsim.facades.canopen_node`,
:mod:`devsim.transports.socketcand`).

python-can's ``can.Notifier`` reads a bus in a thread that waits up to its timeout (1 s; canopen's
``Network.NOTIFIER_CYCLE``) in ``bus.recv`` before it looks whether it was stopped, and its
``stop`` waits for that thread: a simulator with a CANopen node took up to a second per bus to
stop while idle, and woke every second meanwhile.  :class:`BusReader` waits for a frame without a
timeout (no wake-up while the bus is quiet) and :meth:`BusReader.stop` wakes it with a marker put
into the bus's own queue; a reader busy with frames stops after the frame it is delivering, not
after the ones still waiting."""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterable

import can
from can.interfaces.virtual import VirtualBus

__all__ = ["BusReader"]

#: What :meth:`BusReader.stop` puts into the bus's queue: the reader's ``recv`` returns it, and no
#: listener is given it.
_WAKE = can.Message(arbitration_id=0, is_error_frame=True)


class BusReader:
    """Delivers every frame of ``bus`` to ``listeners`` (``can.Listener`` objects or callables of
    one message) from a thread of its own, as ``can.Notifier(bus, listeners)`` does; stands in
    for it where a canopen network keeps its notifier (``stop``, ``exception``)."""

    def __init__(self, bus: VirtualBus, listeners: Iterable[Callable[[can.Message], object]]) -> None:
        self.bus = bus
        self.listeners = list(listeners)
        self.exception: BaseException | None = None  #: what ended the thread, as can.Notifier's
        self._stopped = False
        self._thread = threading.Thread(target=self._run, name=f"devsim CAN reader {bus.channel_info}", daemon=True)
        self._thread.start()

    @property
    def stopped(self) -> bool:
        """:meth:`stop` was called (``can.Notifier.stopped``)."""
        return self._stopped

    def _run(self) -> None:
        try:
            while not self._stopped:
                message = self.bus.recv(None)  # (no timeout: stop() wakes it)
                if message is _WAKE or self._stopped:
                    return
                if message is not None:
                    for listener in self.listeners:
                        listener(message)
        except BaseException as exc:  # kept for canopen's Network.check(), as can.Notifier does
            self.exception = exc
            raise

    def stop(self, timeout: float = 5.0) -> None:
        """The thread ends after the frame it is delivering (frames still waiting are not
        delivered) and is waited for, at most ``timeout`` s: it does not wait for a frame."""
        self._stopped = True
        self.bus.queue.put(_WAKE)
        if threading.current_thread() is not self._thread:
            self._thread.join(timeout)
        for listener in self.listeners:
            stop = getattr(listener, "stop", None)
            if stop is not None:
                stop()
