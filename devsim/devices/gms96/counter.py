"""Counter input (synchronous input): set-point source, ``m49`` gear, ``H22`` measurement, ``Q`` P2.5.

Manual §2.6, §2.3.1 H/m/Q; spec §5.10, §3.8.7, §3.8.9, §3.8.14.

**Counter-input mode** (manual §2.6): an M value < 2 saved with ``s85;170`` selects, from the next
restart (emergency-stop release or power cycle), the quadrature counter input K10/K20 (4x
evaluation) instead of the internal indexer as the set-point source.  Every counted increment moves
the set-point by N23 (1..8) increments: an electronic gear.  Indexer moves are rejected in this mode
(spec §5.10 [R]).

**``m49`` synchronous run** (manual: "integrated function, not documented here"; spec §3.8.9 [R]
leaves it to §5.10).  Simulator choice [R]: ``m49`` couples the set-point to the counter input
while the indexer stays the card's source otherwise: from the moment the command executes, the
set-point is ``x0 + (count − count0) · N23`` with the card's limits — the set-point speed of a pulse
stream is limited to the rapid value M, the set-point stops at the 24-bit position range (spec
§5.1), the following-error monitoring (N20) applies.  Preconditions as for a move (spec §4.2.4:
IDXOFF = 0, controller on, no fault); otherwise the command is skipped like a move
(``rejected_moves``).  With N50 bit 0 = 1 the counter input is the *actual-value* source and
cannot also be the set-point source: ``m49`` is skipped the same way.  In counter-input mode
(M < 2) the set-point already follows the input: ``m49`` is a no-op.  The command keeps the
executor BUSY (like every ``m`` wait, spec §3.8.9) until it is **aborted with #0 or PLC marker
M0.1** (the set-point then brakes with the programmed ramp B and the queue is discarded), or a
fault (emergency stop, monitoring, following error) ends it.

**``H22`` measurement** (manual §2.3.1 H): from ``H22;1`` a min/max memory of the counter input
(counted increments) is kept, each with the axis position (position counter, actual value) at that
moment; ``H22;0`` stops it.  The counter value runs piecewise linear between control events, so its
extremes fall on those events (discrete pulses, rate changes, ``H22;0``), where they are recorded
exactly.  The PLC fetches the data with FB 254 / Accu1 = 22 to the data area from byte address
Accu2; the simulator's stand-ins: ``plc.fb254(22, address)`` for a scripted PLC hook and the config
``h22_data_address`` (copy at ``H22;0``).  Layout [R] (no source gives one): four 32-bit values in
the register layout (spec G31, 24-bit little-endian + sign byte) at address +0 min count, +4
position at min, +8 max count, +12 position at max — each readable with ``T1;6;address+4k``.

**``Q`` P2.5** (manual §2.3.1 Q): the index-mark search uses the reference track of the counter
input (e.g. an extra linear scale) instead of the motor encoder's index marks: marks at the axis
positions ``axis.counter_marks`` (config; none → the search runs until the P3 limit or an abort).

Control API (like the SERS ``encoder.pulses``):

* ``counter.pulses`` (set, signed int): that many 4x-evaluated increments arrive at once; the
  set-point jumps by ``pulses · N23`` (applied when the axis stands; during a
  ``counter.rate_hz`` run the jump waits for the run to stop);
* ``counter.rate_hz`` (set, signed float): a continuous pulse stream; the set-point runs at
  ``rate · N23`` inc/s (the motion status follows the activity);
* ``counter.count`` (read): the counted increments since power-on; ``counter.mode``: active?;
  ``counter.sync``: ``m49`` running?; ``counter.h22``: the measurement memory.

The set-point only follows while the position controller is active (no emergency stop, no
monitoring, no following error); the count always counts.
"""

from __future__ import annotations

from collections.abc import Callable

from devsim.core.axis import Axis
from devsim.core.clock import Clock
from devsim.devices.gms96 import tables
from devsim.devices.gms96.coordinates import Coordinates
from devsim.devices.gms96.feed import Feed
from devsim.devices.gms96.image import STATIC_BYTES
from devsim.devices.gms96.memory import Memory
from devsim.devices.gms96.motion import Indexer
from devsim.devices.gms96.params import NParameters
from devsim.devices.gms96.stage import PowerStage

__all__ = ["CounterInput", "H22_BYTES"]

FOLLOW_ACCEL = 1e9  # the set-point follows the counter input without a ramp of its own
H22_BYTES = 16  # min count, position at min, max count, position at max (4 bytes each)


class CounterInput:
    """The counter input of one card (manual §2.6, §2.3.1 H/m; spec §5.10): counter-input mode,
    ``m49`` and ``H22``."""

    def __init__(
        self,
        *,
        clock: Clock,
        axis: Axis,
        indexer: Indexer,
        params: NParameters,
        stage: PowerStage,
        coordinates: Coordinates,
        feed: Feed,
        memory: Memory,
        h22_address: int | None,
        changed: Callable[[], None],
        record_event: Callable[[str], None],
    ) -> None:
        self.clock = clock
        self.axis = axis
        self.indexer = indexer
        self.params = params
        self.stage = stage
        self.coordinates = coordinates
        self.feed = feed
        self.memory = memory
        self.h22_address = h22_address  # H22;0 copies the measurement there (FB 254/22)
        self.changed = changed
        self.record_event = record_event
        self.active = False
        self.sync = False
        self._count = 0.0
        self.rate = 0.0
        self._since = clock.now()
        self._pending = 0.0
        self.h22_running = False
        self.h22: dict[str, int] | None = None

    @property
    def count(self) -> int:
        """Counted increments: the discrete pulses plus the stream's integral."""
        return int(round(self._count + self.rate * (self.clock.now() - self._since), 6))

    def power_on(self) -> None:
        """The mode is read at restart from the M value in EEPROM (manual §2.6)."""
        self.active = self.feed.eeprom_M < 2
        self.sync = False
        self._count = 0.0
        self.rate = 0.0
        self._since = self.clock.now()
        self._pending = 0.0
        self.h22_running = False
        self.h22 = None

    def following(self) -> bool:
        st = self.stage
        return (self.active or self.sync) and st.controller and not st.estop and not st.monitoring_cause()

    def weight(self) -> int:
        return max(1, min(8, self.params.counter_weight))

    # -- the set-point ------------------------------------------------------------------------
    def _limits(self) -> tuple[float, float]:
        """Physical set-point range: the 24-bit position range (spec §5.1)."""
        c = self.coordinates
        return c.machine_to_physical(tables.POSITION_MIN), c.machine_to_physical(tables.POSITION_MAX)

    def pulses(self, count: int) -> None:
        self._count += int(count)
        if self.following():
            self._pending += int(count) * self.weight()
            self._apply()
        self._h22_sample()

    def _apply(self) -> None:
        axis = self.axis
        if self._pending and not axis.moving:
            lo, hi = self._limits()
            axis.set_position(max(lo, min(hi, axis.position() + self._pending)))
            self._pending = 0.0
            self.indexer.arm_following_error()
            self.changed()

    def set_rate(self, rate_hz: float) -> None:
        self._h22_sample()
        now = self.clock.now()
        self._count += self.rate * (now - self._since)
        self._since = now
        self.rate = float(rate_hz)
        if self.following():
            self._follow_rate()

    def _follow_rate(self) -> None:
        axis = self.axis
        if self.rate:
            speed = abs(self.rate) * self.weight()
            if self.sync and not self.active:
                speed = min(speed, float(max(self.feed.M, 1)))  # m49: limited to rapid M
            lo, hi = self._limits()
            axis.move_to(hi if self.rate > 0 else lo, speed, FOLLOW_ACCEL, on_done=self._apply)
        elif axis.moving:
            axis.stop(FOLLOW_ACCEL, self._apply)
        self.indexer.arm_following_error()
        self.changed()

    # -- m49 synchronous run --------------------------------------------------------------------
    def start_sync(self) -> bool:
        """``m49``: couple the set-point to the counter input; False if it cannot (skipped)."""
        if self.active:
            return True  # the counter input already is the set-point source
        if self.params.binary_options & 1 or not self.stage.ready():
            return False
        self.indexer.target = None
        self.indexer.jog_dir = 0
        self.sync = True
        self._pending = 0.0
        self.record_event("sync_start")
        if self.rate:
            self._follow_rate()
        self.changed()
        return True

    def stop_sync(self, on_stopped: Callable[[], None] | None = None) -> bool:
        """End ``m49`` (abort/fault): the set-point brakes with the card's ramp; True if it ran."""
        if not self.sync:
            return False
        self.sync = False
        self._pending = 0.0
        self.record_event("sync_end")
        self.indexer.halt(on_stopped)
        return True

    # -- H22 measurement --------------------------------------------------------------------------
    def _position(self) -> int:
        return int(round(self.coordinates.physical_to_machine(self.indexer.actual())))

    def h22_start(self) -> None:
        c, x = self.count, self._position()
        self.h22 = {"min": c, "min_position": x, "max": c, "max_position": x}
        self.h22_running = True

    def _h22_sample(self) -> None:
        if not self.h22_running or self.h22 is None:
            return
        c = self.count
        if c < self.h22["min"]:
            self.h22["min"], self.h22["min_position"] = c, self._position()
        if c > self.h22["max"]:
            self.h22["max"], self.h22["max_position"] = c, self._position()

    def h22_stop(self) -> None:
        if not self.h22_running:
            return
        self._h22_sample()
        self.h22_running = False
        address = self.h22_address
        if address is not None:
            self.h22_copy(address)

    def h22_copy(self, address: int) -> None:
        """FB 254 / 22: the measurement into the data area from byte ``address`` (layout above)."""
        data = self.memory.image.data
        if not 0 <= address <= len(data) - H22_BYTES:
            return
        self._h22_sample()
        h = self.h22 or {"min": 0, "min_position": 0, "max": 0, "max_position": 0}
        for k, key in enumerate(("min", "min_position", "max", "max_position")):
            value = max(-0x800000, min(0x7FFFFF, h[key]))
            raw = (value & 0xFFFFFF).to_bytes(3, "little") + (b"\xff" if value < 0 else b"\x00")
            data[address + 4 * k : address + 4 * k + 4] = raw
        if address < STATIC_BYTES:
            self.memory.save_static()  # DW0..79 are static (spec §3.8.4)

    def state(self) -> dict[str, object]:
        self._h22_sample()
        return {
            "mode": self.active,
            "sync": self.sync,
            "count": self.count,
            "rate_hz": self.rate,
            "weight": self.weight(),
            "h22": dict(self.h22) if self.h22 is not None else None,
            "h22_running": self.h22_running,
        }
