"""A tiny device kind for tests that must not depend on a real controller.

``EchoDevice`` echoes every byte it receives (unless ``input.mute`` is set; parameter ``P1``
times each), counts them, and has a timer driven by the device clock so that tests can watch
simulated time move.  Register it with ``DEVSIM_EXTRA_KINDS="echo=tests.support.echo:EchoDevice"``.

It is also the smallest kind, in one file, with every table a kind declares (README, "Adding a
kind"; docs/kind-shape.md): configuration (:class:`EchoConfig`), parameters as kit rows
(:data:`PARAMETERS`, read by the model through :class:`EchoParameters`' named accessor), signals,
points (:data:`POINTS`), a face per port (:class:`EchoFace`) and the reference.  A shipped kind
splits the same into ``devsim/devices/KIND/{config,tables,model,face,points,device}.py`` and is
registered by its entry point in ``pyproject.toml``.
"""

from __future__ import annotations

from typing import Annotated, Any, ClassVar

from devsim.core.clock import Timer
from devsim.core.device import Device, Face, SerialSettings
from devsim.core.kit import PortDef, Reference, SignalDef, declare_signals, signal_points
from devsim.core.model import Model
from devsim.core.parameters import Param, Parameters, ParameterTable, accessor, alias_hook, parameter_points
from devsim.core.points import Point, PointTable
from devsim.core.settings import Check, Meta, Settings, field

BAUDS = (1200, 2400, 4800, 9600, 19200)


def _baud(value: int) -> int:
    if value not in BAUDS:
        raise ValueError(f"baud must be one of {', '.join(map(str, BAUDS))}")
    return value


class EchoGeometry(Settings):
    """where the (imaginary) switches sit"""

    limit_left: float | None = None
    limit_right: float | None = None


class EchoConfig(Settings):
    """what a user can set for an echo device"""

    address: Annotated[int, Meta(ge=0, le=127)] = 1
    baud: Annotated[int, Check(_baud)] = 9600
    greeting: str = ""
    axis: EchoGeometry = field(default_factory=EchoGeometry)


ECHO_GEOMETRY = EchoGeometry

#: The echo's parameters, one kit row each (a real kind cites its manual's section).
PARAMETERS = ParameterTable(
    (Param(1, "Wiederholung", "(test device)", "how many times each byte is echoed", minimum=1, maximum=4,
           default=1, saved=False, attr="repeat"),),
    prefix="P",
)


class EchoParameters(Parameters):
    """The echo's parameter values; the model reads them by name."""

    repeat = accessor(1)


class EchoModel(Model):
    """The echo "machine": a mute input, a value, a byte counter and a timer on the device clock."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.settings = EchoConfig.parse(self.config)
        declare_signals(self.signals, SIGNALS)
        self.params = EchoParameters(PARAMETERS)
        self.value: float = 0
        self.received = 0
        self.largest = 0  # the biggest chunk of host bytes handed over at once
        self.fired = False
        self._timer: Timer | None = None
        self.boots = 1

    def start_timer(self, seconds: float) -> None:
        if self._timer is not None:
            self._timer.cancel()
        self.fired = False
        self._timer = self.clock.call_later(seconds, self._fire)

    def _fire(self) -> None:
        self.fired = True
        self._timer = None

    def power_cycle(self, *, wipe: bool = False) -> None:
        super().power_cycle(wipe=wipe)
        self.boots += 1
        self.received = 0

    def close(self) -> None:
        if self._timer is not None:
            self._timer.cancel()


class EchoFace(Face):
    """Echoes the host's bytes unless ``input.mute`` is set."""

    model: EchoModel

    @property
    def serial_settings(self) -> SerialSettings:
        return SerialSettings(baudrate=self.model.settings.baud)

    def feed(self, data: bytes) -> None:
        self.model.received += len(data)
        self.model.largest = max(self.model.largest, len(data))
        if not self.model.signals.get("mute"):
            repeat = self.model.params.repeat
            self.send(data if repeat == 1 else bytes(b for b in data for _ in range(repeat)))


SIGNALS = (SignalDef("mute", "input", False, "echo nothing while set"),)

POINTS = PointTable.of(
    signal_points(SIGNALS),
    parameter_points(PARAMETERS, lambda m, row: m.params[row.key], lambda m, row, v: m.params.set(row.key, v)),
    [
        Point("value", "float", "a free number", get=lambda m: m.value, put=lambda m, v: setattr(m, "value", v)),
        Point("received", "int", "bytes received since power-on", get=lambda m: m.received, in_state=True),
        Point("largest", "int", "the biggest chunk of host bytes fed at once", get=lambda m: m.largest),
        Point("fired", "bool", "the timer has fired", get=lambda m: m.fired, in_state=True),
        Point("timer", "float", "start the timer (seconds)", unit="s", put=lambda m, v: m.start_timer(v), minimum=0),
        Point("now", "float", "the device clock", unit="s", get=lambda m: m.clock.now()),
        Point("address", "int", "the configured address", get=lambda m: m.settings.address, in_state=True),
        Point("boots", "int", "power-ons so far", get=lambda m: m.boots),
        Point(
            "nvram.note",
            "json",
            "a value kept in non-volatile memory",
            get=lambda m: m.nvram.get("note"),
            put=lambda m, v: m.nvram.put("note", v),
        ),
    ],
    alias=alias_hook(PARAMETERS),
)


class EchoDevice(Device):
    """Echoes bytes back; a test stand-in for a controller."""

    kind: ClassVar[str] = "echo"
    description: ClassVar[str] = "Echoes every byte back (test device)"
    config_model = EchoConfig
    ports = (PortDef(address="address"),)  # (several on one line: devsim run echo --drives 3,5)
    model_class = EchoModel
    face_classes: ClassVar[dict[str, Any]] = {"main": EchoFace}
    points = POINTS

    @classmethod
    def reference(cls) -> Reference:
        return Reference(parameter_table=PARAMETERS)
