"""A tiny device kind for tests that must not depend on a real controller.

``EchoDevice`` echoes every byte it receives (unless ``input.mute`` is set), counts them, and
has a timer driven by the device clock so that tests can watch simulated time move.  Register it
with ``DEVSIM_EXTRA_KINDS="echo=tests.support.echo:EchoDevice"``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar

from pydantic import BaseModel, ConfigDict, Field, field_validator

from devsim.core.clock import Timer
from devsim.core.device import Device, SerialSettings, UnknownName

BAUDS = (1200, 2400, 4800, 9600, 19200)


class EchoGeometry(BaseModel):
    model_config = ConfigDict(extra="forbid")

    limit_left: float | None = None
    limit_right: float | None = None


class EchoConfig(BaseModel):
    model_config = ConfigDict(extra="forbid")

    address: int = Field(default=1, ge=0, le=127)
    baud: int = 9600
    greeting: str = ""
    axis: EchoGeometry = Field(default_factory=EchoGeometry)

    @field_validator("baud")
    @classmethod
    def _baud(cls, value: int) -> int:
        if value not in BAUDS:
            raise ValueError(f"baud must be one of {', '.join(map(str, BAUDS))}")
        return value


class EchoDevice(Device):
    """Echoes bytes back; a test stand-in for a controller."""

    kind: ClassVar[str] = "echo"
    description: ClassVar[str] = "Echoes every byte back (test device)"
    config_model: ClassVar[type[BaseModel]] = EchoConfig

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.settings = EchoConfig.model_validate(self.config)
        self.signals.define("input.mute", "input", False)
        self.signals.define("value", "quantity", 0)
        self.received = 0
        self.fired = False
        self._timer: Timer | None = None
        self.boots = 1

    @property
    def serial_settings(self) -> SerialSettings:
        return SerialSettings(baudrate=self.settings.baud)

    def feed(self, data: bytes) -> None:
        self.received += len(data)
        if not self.signals.get("input.mute"):
            self.send(data)

    def read(self, name: str) -> Any:
        if name in self.signals:
            return self.signals.get(name)
        simple: Mapping[str, Any] = {
            "received": self.received,
            "fired": self.fired,
            "now": self.clock.now(),
            "address": self.settings.address,
            "boots": self.boots,
            "nvram.note": self.nvram.get("note"),
        }
        if name in simple:
            return simple[name]
        raise UnknownName(f"echo has no {name!r}")

    def set(self, name: str, value: Any) -> None:
        if name == "timer":
            if self._timer is not None:
                self._timer.cancel()
            self.fired = False
            self._timer = self.clock.call_later(float(value), self._fire)
            return
        if name == "nvram.note":
            self.nvram.put("note", value)
            return
        if name not in self.signals or self.signals.signal(name).kind == "output":
            raise UnknownName(f"echo has no settable {name!r}")
        self.signals.set(name, value)

    def _fire(self) -> None:
        self.fired = True
        self._timer = None

    def state(self) -> dict[str, Any]:
        return {
            "address": self.settings.address,
            "received": self.received,
            "fired": self.fired,
            "signals": self.signals.snapshot(),
        }

    def power_cycle(self, *, wipe: bool = False) -> None:
        super().power_cycle(wipe=wipe)
        self.boots += 1
        self.received = 0

    def close(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
