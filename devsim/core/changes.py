"""The moments anything may have changed a device of this process, counted (issue 31).

A device changes only through a few doors, and each counts here (``CHANGES.count += 1``,
before it lets the change in):

* bytes reaching a face (:meth:`devsim.core.device.Port.feed`; a host that disconnects);
* a timer of the device clock firing (:class:`devsim.core.clock.RealClock`,
  :class:`~devsim.core.clock.VirtualClock`): motion events, program steps, boot ends;
* the control API putting a point (:meth:`devsim.core.points.PointTable.set`,
  :meth:`devsim.core.device.Device.apply_state`, the fleet's fast ``set``), switching a fault or
  the power (:meth:`~devsim.core.device.Device.fault`, :meth:`~devsim.core.device.Device.power_cycle`),
  a runner's hint (:meth:`~devsim.core.device.Device.unobserved_until`);
* a bus sharing the line (:class:`devsim.core.bus.Bus`), a facade's drive actions
  (:class:`devsim.facades.cia402.Cia402`).

Reading a point changes nothing.  A face that made an answer when the count stood at N may give
the same answer again while the count still stands at N without looking again at the state it
depends on (a SERS's repeated poll, :meth:`devsim.devices.sers.polls.KeptPolls.answer_at_once`:
the checks it would repeat touch about a dozen objects of the drive, and a plant's devices are
cold in the processor's caches between their polls).  A value that changes with time alone
(a position while the axis moves) is no state here: such a face reads it every time.  Code that
changes a model by another way (a test reaching into ``device.model``) counts here itself.
The count is one per process, not per device: a change anywhere costs every face one full look.
"""

from __future__ import annotations

__all__ = ["CHANGES", "Changes"]


class Changes:
    """The count (one attribute, slots: every poll reads it)."""

    __slots__ = ("count",)

    def __init__(self) -> None:
        self.count = 0


#: The process's count.
CHANGES = Changes()
