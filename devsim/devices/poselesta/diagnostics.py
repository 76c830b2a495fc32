"""The diagnostic pages of program P79 (manual §2.3.25, §2.3.26, §2.4.11; spec poselesta.md
§4.7, vector §6.11): N5, the levels of all inputs as four ports of two bytes; N6, the output test;
N7, the feed and override pot voltages as hex 00 … FF."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from devsim.core.clock import Clock, Timer
from devsim.core.points import BadValue
from devsim.core.signals import SignalBank

__all__ = ["INPUT_IMAGE", "OUTPUT_GROUPS", "OutputTest", "input_image", "input_screen", "pots"]

#: P79 N5: port and half → the input of bit 7 … bit 0 (None: unused).
INPUT_IMAGE: dict[str, tuple[str | None, ...]] = {
    "1A": ("open_loop", "key_switch", "keyboard_external", "optional_stop", "xy_plotter", "program_lock_open",
           "block_abort", None),
    "1B": ("jog_step_10000", "jog_step_1000", "jog_step_100", "jog_step_10", "jog_step_1", "m10_ack", "rapid",
           "mst_ack"),
    "2A": ("limit_pos_d", "limit_pos_z", "limit_pos_y", "limit_pos_x", "limit_neg_d", "limit_neg_z", "limit_neg_y",
           "limit_neg_x"),
    "2B": ("jog_pos_d", "jog_pos_z", "jog_pos_y", "jog_pos_x", "jog_neg_d", "jog_neg_z", "jog_neg_y", "jog_neg_x"),
    "3A": (None, None, None, None, "handwheel_d", "handwheel_z", "handwheel_y", "handwheel_x"),
    "3B": (None,) * 8,
    "4A": ("tool_change_ack", "program_continue", "axis_enable", "inch", None, "block_skip_cancel", None, None),
    "4B": (None, None, "nc_start", "emergency_stop", "nc_stop", None, None, None),
}


def input_image(signals: SignalBank) -> dict[str, int]:
    """Each half-port as a byte: bit = 1 where the input is H."""
    image = {}
    for port, names in INPUT_IMAGE.items():
        value = 0
        for bit, name in zip(range(7, -1, -1), names, strict=True):
            if name is not None and signals.get(name):
                value |= 1 << bit
        image[port] = value
    return image


def input_screen(signals: SignalBank) -> str:
    """The page as the monitor shows it: ``Port 1 EIN 01000110 00000000`` …"""
    image = input_image(signals)
    return "\n".join(f"Port {n} EIN {image[f'{n}A']:08b} {image[f'{n}B']:08b}" for n in range(1, 5))


def pots(signals: SignalBank) -> list[Any]:
    """P79 N7: feed and override pot as ``round(V / 10 × 255)`` in hex."""
    return [f"{round(max(0.0, min(10.0, float(signals.get(name)))) / 10 * 255):02X}"
            for name in ("feed_pot_v", "override_pot_v")]


#: P79 N6: the outputs of V15, V16 and V18, contact 1 … 8 (None: no contact); V17 is the bus.
OUTPUT_GROUPS: tuple[tuple[str | None, ...], ...] = (
    ("m00", "m01", "m02", "m03", "m04", "m06", "m08", "m10"),
    ("strobe_m", "strobe_s1", "strobe_s2", "strobe_t", "strobe_ba", "buzzer", None, "start_stop_status"),
    ("travel_x", "travel_y", "travel_z", "travel_d", "position_reached", "inside_working_field", "nc_ready",
     "machine_standstill"),
)
OUTPUT_TEST_STEP = 0.25  # s: 256 steps = 64 s per pass (spec §4.7, G-DIAG6)


class OutputTest:
    """P79 N6 (§2.4.11): every output in ascending binary code, one step each 250 ms, a pass
    counter; "C" stops it with all outputs L, and the control then needs a power cycle.  It
    runs whatever NC-Stop and Not-Stop say: the outputs must be disconnected from the machine.
    ``may_start()`` says whether the diagnostic programs can run (PROGRAM_ENTRY, no block)."""

    def __init__(self, clock: Clock, signals: SignalBank, record: Callable[[str], None], *,
                 may_start: Callable[[], bool]) -> None:
        self._clock = clock
        self._signals = signals
        self._record = record
        self._may_start = may_start
        self.running = False
        self.stopped = False  # "C" pressed: normal operation only after a power cycle
        self.count = 0
        self.cycles = 0
        self._timer: Timer | None = None

    def start(self) -> None:
        if not self._may_start():
            raise BadValue("the diagnostic programs P79 run in PROGRAM_ENTRY")
        self.running, self.count, self.cycles = True, 0, 0
        self._show()

    def _show(self) -> None:
        for group in OUTPUT_GROUPS:
            for bit, name in enumerate(group):
                if name is not None:
                    self._signals.set(name, bool(self.count >> bit & 1))
        self._signals.set("data_bus", self.count)
        self._timer = self._clock.call_later(OUTPUT_TEST_STEP, self._step)

    def _step(self) -> None:
        self.count = (self.count + 1) % 256
        if self.count == 0:
            self.cycles += 1
        self._show()

    def stop(self) -> None:
        """Key "C": all outputs L; the control stays so until it is switched off and on."""
        if not self.running:
            return
        self.cancel()
        self.stopped = True
        for group in OUTPUT_GROUPS:
            for name in group:
                if name is not None:
                    self._signals.set(name, False)
        self._signals.set("data_bus", 0)
        self._record("output_test_stopped")

    def cancel(self) -> None:
        self.running = False
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
