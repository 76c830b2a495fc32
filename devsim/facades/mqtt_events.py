"""The moments that make the MQTT facade publish at once, not only at its sampling tick (issue 29).

A :class:`~devsim.core.watch.PointWatch` samples every ``rate`` seconds of device time; a move
of 0.25 s between two samples of a 1 s rate would never show ``motion: true``.  So the facade
also samples when the model says something happened, through the hooks the watch stream
(:mod:`devsim.runtime.watch_stream`) and the motion log listen to:

* the model's ``recorded`` moments (``move_start``, ``move_end``, errors …,
  :meth:`devsim.core.model.Model.record_event`);
* a declared fault switched (``fault_switched``) and the model's own drive ``fault``;
* an input or output signal that changed (:meth:`devsim.core.signals.SignalBank.subscribe`).

A model announces a moment before it has finished the step that makes it (the SERS records
``move_start`` and then sets its motion), so the sample is taken right after the step, at the same
instant of device time: a timer of the device clock due now (it runs inside a virtual
``advance``) and, for a step that ran outside one, the loop's next turn; whichever comes first
samples, the other is cancelled.  Several moments of one step give one sample.  Nothing polls:
an idle device hears nothing and samples only at its tick.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import Any

from devsim.core.device import Device

__all__ = ["MOMENTS", "SIGNAL_KINDS", "SampleOnEvent"]

#: The model topics (:meth:`devsim.core.model.Model.listen`) after which the points are sampled.
MOMENTS = ("recorded", "fault_switched", "fault")
#: The signal kinds whose changes are sampled after (quantities are analog and sampled at the tick).
SIGNAL_KINDS = ("input", "output")


class SampleOnEvent:
    """Call ``sample()`` once right after each step of ``device``'s model that announced a
    moment or changed an input or output (see the module docstring)."""

    def __init__(self, device: Device, sample: Callable[[], Any]) -> None:
        self.device = device
        self.sample = sample
        self._undo: list[Callable[[], Any]] = []
        self._timer: Any = None
        self._handle: asyncio.Handle | None = None
        self._sampling = False

    def start(self) -> None:
        model = self.device.model
        for topic in MOMENTS:
            self._undo.append(model.listen(topic, self._moment))
        signals = model.signals
        for kind in SIGNAL_KINDS:
            for name in signals.names(kind):  # type: ignore[arg-type]
                self._undo.append(signals.subscribe(name, self._moment))

    def _moment(self, *_args: Any) -> None:
        if self._timer is not None or self._sampling:  # one sample per step; none from our own reads
            return
        self._timer = self.device.clock.call_later(0.0, self._fire)
        try:
            self._handle = asyncio.get_running_loop().call_soon(self._fire)
        except RuntimeError:  # no loop in this thread: the clock's timer alone
            self._handle = None

    def _fire(self) -> None:
        self._cancel()
        self._sampling = True
        try:
            self.sample()
        finally:
            self._sampling = False

    def _cancel(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        if self._handle is not None:
            self._handle.cancel()
            self._handle = None

    def stop(self) -> None:
        self._cancel()
        for undo in self._undo:
            undo()
        self._undo.clear()
