"""The card's 24 V inputs and outputs and the in-position signal (manual §2.4.2, §2.3.1 N21/N27/N28,
T1;1/T1;2; spec §4.11, §5.5).

Outputs A0.0..A1.2 (A0.0..A0.5 on the K1, the outputs its hardware has: manual §2.4.2, §6) come
from the process image, except A0.0 as the brake output (N21 at the start: on while the position
controller drives) and A0.1 as in-position (N27 > 0); an overload of the 24 V outputs switches
them all off (E2.2 shows it).
"""

from __future__ import annotations

import math
from collections.abc import Callable

from devsim.core.axis import Axis
from devsim.core.clock import Clock, Timer
from devsim.core.settings import Settings
from devsim.core.signals import SignalBank
from devsim.devices.gms96.image import ProcessImage
from devsim.devices.gms96.motion import ActualSwitch, Indexer
from devsim.devices.gms96.params import NParameters
from devsim.devices.gms96.stage import PowerStage

__all__ = ["INPUT_BYTES", "OUTPUT_BITS", "Outputs", "axis_switches", "inputs_shown_at"]

INPUT_BYTES = 4  # EB0..EB3
OUTPUT_BITS = 11  # A0.0..A1.2 (spec §4.11.1, G27)

#: Inputs shown OR-ed with another on KSA cards and under an interpolation card (manual §2.4.2,
#: §4.4, §5.2): E1.6 with E2.0, E1.7 with E2.1, both ways.
ORED_INPUTS: dict[tuple[int, int], str] = {(1, 6): "E2.0", (2, 0): "E1.6", (1, 7): "E2.1", (2, 1): "E1.7"}
#: The names of the input bits, by byte: E0.0 … E3.7.
_INPUT_NAMES = tuple(tuple(f"E{byte}.{bit}" for bit in range(8)) for byte in range(INPUT_BYTES))
#: The monitoring cause a resolver card shows at E2.3 (manual §2.4.2: "E2.3 = Ausfall Resolver").
RESOLVER_LOSS = "resolver_loss"
#: K1: its inputs E0.4 and E0.5 are also shown at E2.0 and E2.1 (manual §5.2).
K1_SHOWN_AT: dict[tuple[int, int], str] = {(2, 0): "E0.4", (2, 1): "E0.5"}


def inputs_shown_at(variant: str, interpolation: bool) -> dict[tuple[int, int], str]:
    """Which inputs the image shows OR-ed into another bit: K1's E0.4/E0.5 at E2.0/E2.1; on KSA
    cards and behind an interpolation card E1.6/E1.7 with E2.0/E2.1 (manual §2.4.2, §4.4, §5.2)."""
    if variant == "K1":
        return K1_SHOWN_AT
    if interpolation or variant.startswith("KSA"):
        return ORED_INPUTS
    return {}


class Outputs:
    """Inputs and outputs of one card as the host (T1;1, T1;2), the PLC and the waits see them
    (manual §2.4.2; spec §4.11)."""

    def __init__(
        self,
        clock: Clock,
        axis: Axis,
        image: ProcessImage,
        signals: SignalBank,
        params: NParameters,
        stage: PowerStage,
        indexer: Indexer,
        stepper: bool,
        changed: Callable[[], None],
        *,
        shown_at: Callable[[], dict[tuple[int, int], str]] = dict,
        resolver: bool = False,
        fitted_outputs: int = OUTPUT_BITS,
    ) -> None:
        self.clock = clock
        self.axis = axis
        self.image = image
        self.signals = signals
        self.params = params
        self.stage = stage
        self.indexer = indexer
        self.stepper = stepper
        self.changed = changed
        #: The inputs the variant (and the DIL switch) also show at another bit: {(byte, bit): input}.
        self.shown_at = shown_at
        self.resolver = resolver  # the card has a resolver: its signal loss shows at E2.3
        #: The outputs the variant's hardware has, from A0.0 (manual §2.4.2: "Hardware bestückt bis
        #: A0.5 (K/K1)"; §6): the process image holds A0.0..A1.7 whatever the card, the 24 V outputs
        #: beyond these never switch.
        self.fitted_outputs = fitted_outputs
        self._inpos_timer: Timer | None = None
        self._inpos_fired = -math.inf

    # -- outputs ------------------------------------------------------------------------------
    def output_bit(self, n: int) -> bool:
        stage = self.stage
        if stage.overload_latched:
            return False
        if n == 0 and stage.brake_output:
            return stage.controller and not stage.estop and not stage.monitoring_cause()
        if n == 1 and self.params.in_position_window > 0:
            return self.in_position()
        return bool(self.image.outputs[n // 8] >> (n % 8) & 1)

    def write_output(self, n: int, value: bool) -> None:
        byte, bit = divmod(n, 8)
        if value:
            self.image.outputs[byte] |= 1 << bit
        else:
            self.image.outputs[byte] &= ~(1 << bit) & 0xFF
        self.changed()

    def output_byte(self, byte: int) -> int:
        if byte == 2:
            return 0 if self.stage.overload_latched else self.image.outputs[2]
        if not 0 <= byte < 2:
            return 0  # beyond the image (T1;2 from a negative byte too)
        return sum(1 << b for b in range(8) if byte * 8 + b < 16 and self.output_bit(byte * 8 + b))

    def input_bit(self, byte: int, bit: int) -> bool:
        """An input as the image shows it: its own signal, OR-ed with the one the variant wires
        to it (:data:`ORED_INPUTS`, :data:`K1_SHOWN_AT`)."""
        if bool(self.signals.get(f"E{byte}.{bit}")):
            return True
        other = self.shown_at().get((byte, bit))
        return other is not None and bool(self.signals.get(other))

    def input_byte(self, byte: int) -> int:
        """EB(byte) as the image shows it: :meth:`input_bit` of its eight bits."""
        if not 0 <= byte < INPUT_BYTES:
            return 0
        get, shown = self.signals.get, self.shown_at()
        value = 0
        for bit, name in enumerate(_INPUT_NAMES[byte]):
            if get(name):
                value |= 1 << bit
            else:
                other = shown.get((byte, bit))
                if other is not None and get(other):
                    value |= 1 << bit
        if byte == 2 and self.stage.overload_latched:
            value |= 0x04  # E2.2: 24 V short circuit
        if byte == 2 and self.resolver and self.stage.monitoring_cause() == RESOLVER_LOSS:
            value |= 0x08  # E2.3: resolver failure
        return value

    def follow(self) -> None:
        """The output signals of the fitted outputs follow the state; the others stay off."""
        fitted = self.fitted_outputs
        for n in range(16):
            self.signals.set(f"A{n // 8}.{n % 8}", self.output_bit(n) if n < fitted else False)

    # -- in position (spec §5.5) ----------------------------------------------------------------
    def in_position(self) -> bool:
        """Spec §5.5: set-point finished and |e| <= |N27| for >= N28 ms (while the axis stands the
        modelled following error is constant, so the N28 time runs from the set-point's stop);
        N27 = 0 (or a stepper card): set-point finished."""
        since = self.axis.stopped_since()
        if since is None:
            return False
        window = abs(self.params.in_position_window)
        if window == 0 or self.stepper:
            return True
        if abs(self.indexer.following_error()) > window:
            return False
        return self.clock.now() >= since + self.params.in_position_time_ms / 1000.0

    def arm_in_position(self) -> None:
        """Re-evaluate the outputs and waits (A0.1, H2) when the set-point stops and N28 later."""
        if self._inpos_timer is not None:
            self._inpos_timer.cancel()
            self._inpos_timer = None
        segs = self.axis.segments() if self.axis.moving else []
        end = segs[-1].t1 if segs else self.axis.stopped_since()
        if end is None or end == math.inf:
            return
        now = self.clock.now()
        for due in (end, end + self.params.in_position_time_ms / 1000.0):
            if due >= now and due > self._inpos_fired:
                self._inpos_timer = self.clock.call_at(due, lambda due=due: self._in_position_tick(due))
                return

    def _in_position_tick(self, due: float) -> None:
        self._inpos_timer = None
        self._inpos_fired = due
        self.arm_in_position()
        self.changed()


def axis_switches(indexer: Indexer, signals: SignalBank, geometry: Settings) -> list[ActualSwitch]:
    """The configured reference cam and position ranges wired to inputs (spec §5.6, §5.11).
    They act on the ACTUAL position (set-point - v/Kv): they switch v/Kv later than the
    set-point passes them."""
    switches = []
    if geometry.cam is not None:
        lo, hi = geometry.cam
        nc = geometry.cam_polarity == "NC"

        def cam(active: bool) -> None:
            signals.set(geometry.cam_input, active != nc)

        sw = ActualSwitch(indexer, lo, hi, cam)
        switches.append(sw)
        signals.signal(geometry.cam_input).value = sw.active != nc
    for ls in geometry.limit_switches:
        name = ls.input

        def follow(active: bool, name: str = name) -> None:
            signals.set(name, active)

        sw = ActualSwitch(indexer, -math.inf if ls.low is None else ls.low, math.inf if ls.high is None else ls.high, follow)
        switches.append(sw)
        signals.signal(name).value = sw.active
    return switches
