"""The plant file's building blocks for one device (spec pieces shared by plants and scenarios):
durations, the transport a port is served on, and the fieldbus and IT facades (Modbus, CANopen,
MQTT, OPC UA) a device or plant adds.  :mod:`devsim.scenario.schema` puts them together."""

from __future__ import annotations

import math
import re
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationInfo, field_validator, model_validator

__all__ = [
    "CanopenSpec",
    "ModbusSpec",
    "MqttSpec",
    "OpcuaSpec",
    "PtySpec",
    "SpecModel",
    "TcpSpec",
    "TransportSpec",
    "parse_duration",
]

_UNITS = {"ms": 0.001, "s": 1.0, "sec": 1.0, "min": 60.0, "m": 60.0, "h": 3600.0, "us": 1e-6}
_DURATION = re.compile(r"\s*([0-9]*\.?[0-9]+)\s*(ms|us|s|sec|min|m|h)?\s*")


def parse_duration(value: Any, field: str = "duration") -> float:
    """``2s``, ``150ms``, ``1.5 min`` or a plain number of seconds → seconds."""
    if isinstance(value, bool):
        raise ValueError(f"`{field}` must be a duration like 2s or 150ms")
    if isinstance(value, int | float):
        if value < 0 or not math.isfinite(value):
            raise ValueError(f"`{field}` must be a duration like 2s or 150ms")
        return float(value)
    if isinstance(value, str):
        match = _DURATION.fullmatch(value)
        if match:
            return float(match.group(1)) * _UNITS[match.group(2) or "s"]
    raise ValueError(f"`{field}` must be a duration like 2s or 150ms")


class SpecModel(BaseModel):
    """A spec with no unknown keys."""

    model_config = ConfigDict(extra="forbid")


# -- ports and facades ----------------------------------------------------------------------
class PtySpec(SpecModel):
    link: str | None = None


class TcpSpec(SpecModel):
    port: int = Field(default=0, ge=0, le=65535)
    host: str = "127.0.0.1"


_TRANSPORTS = ("pty", "tcp", "rfc2217", "udp", "bus")


class TransportSpec(SpecModel):
    """Exactly one of ``pty``, ``tcp``, ``rfc2217``, ``udp`` or ``bus`` (the name of a bus)."""

    pty: PtySpec | None = None
    tcp: TcpSpec | None = None
    rfc2217: TcpSpec | None = None
    udp: TcpSpec | None = None
    bus: str | None = None

    @model_validator(mode="after")
    def _one(self) -> TransportSpec:
        given = [k for k in _TRANSPORTS if getattr(self, k) is not None]
        if len(given) > 1:
            raise ValueError(f"give one transport, not {' and '.join(given)}")
        if not given:
            self.pty = PtySpec()
        return self

    @property
    def kind(self) -> str:
        return next(k for k in _TRANSPORTS if getattr(self, k) is not None)


class ModbusSpec(SpecModel):
    """The device also on Modbus (issue 13): ``{tcp: {port: 5020}}`` (Modbus TCP) or ``{rtu: {}}``
    (Modbus RTU on a pty, ``{rtu: {link: /tmp/ttyMB}}`` with a symlink); ``unit`` its unit id,
    ``line`` the RTU line settings (``19200 8E1``);
    ``map`` overrides entries of the generated register map (``{name: {address, table, scale}}``
    or ``{name: null}``)."""

    tcp: TcpSpec | None = None
    rtu: PtySpec | None = None
    unit: int = Field(default=1, ge=1, le=247)
    line: str = Field(default="19200 8E1", description="RTU line settings")
    layout: Literal["points", "mirror"] = Field(default="points", description="the map: generated from the points,"
                                                " or the kind's own mirror (PCD4.H3: its media, spec §9.8)")
    map: dict[str, Any] = Field(default_factory=dict)

    @model_validator(mode="after")
    def _one(self) -> ModbusSpec:
        if (self.tcp is None) == (self.rtu is None):
            raise ValueError("give tcp or rtu")
        return self

    def spec(self) -> str:
        """The ``--modbus`` form: ``tcp:HOST:PORT``, ``rtu`` or ``rtu:LINK``."""
        if self.tcp is not None:
            return f"tcp:{self.tcp.host}:{self.tcp.port}"
        assert self.rtu is not None
        return f"rtu:{self.rtu.link}" if self.rtu.link else "rtu"


class CanopenSpec(SpecModel):
    """A device as a CANopen node (issue 13): its node id and the CAN network it joins, a
    socketcand server at ``[HOST:]PORT`` (the plant's devices with the same network share one bus)
    or ``socketcan:CHANNEL``."""

    node: int = Field(ge=1, le=127, description="the node id")
    network: str = Field(default="127.0.0.1:29536", pattern=r"^(socketcan:\S+|(\S+:)?\d+)$",
                         description="[HOST:]PORT of a socketcand server, or socketcan:CHANNEL")


class MqttSpec(SpecModel):
    """The plant's devices also over MQTT (issue 14, :mod:`devsim.facades.mqtt`): ``url``
    ``mqtt://HOST[:PORT]`` of the broker (none: an embedded broker on loopback), ``convention``
    ``devsim`` or ``sparkplug``, ``rate`` how often the points are sampled for changes (device
    time), ``plant`` the plant's name in the topics (default: the plant's ``name``)."""

    url: str | None = None
    convention: Literal["devsim", "sparkplug"] = "devsim"
    rate: float = Field(default=1.0, description="seconds (or a duration like 500ms) between samples")
    plant: str | None = None

    @field_validator("rate", mode="before")
    @classmethod
    def _duration(cls, value: Any) -> float:
        seconds = parse_duration(value, "rate")
        if not seconds > 0:
            raise ValueError("`rate` must be a positive duration like 1s or 500ms")
        return seconds

    @field_validator("url")
    @classmethod
    def _url(cls, value: str | None) -> str | None:
        if value is not None:
            from devsim.facades.mqtt_topics import parse_url

            parse_url(value)
        return value
class OpcuaSpec(SpecModel):
    """The plant's devices on one OPC UA server (issue 14, :mod:`devsim.facades.opcua`):
    ``opcua: {}`` serves ``opc.tcp://127.0.0.1:4840/devsim/``; ``port: 0`` takes a free port;
    ``period`` is how often the points are sampled for subscriptions (device time)."""

    host: str = "127.0.0.1"
    port: int = Field(default=4840, ge=0, le=65535)
    period: float = Field(default=0.1, gt=0, description="sampling period for subscriptions, e.g. 100ms")

    @field_validator("period", mode="before")
    @classmethod
    def _duration(cls, value: Any, info: ValidationInfo) -> float:
        return parse_duration(value, str(info.field_name))

    def spec(self) -> str:
        """The ``--opcua`` form: ``HOST:PORT``."""
        return f"[{self.host}]:{self.port}" if ":" in self.host else f"{self.host}:{self.port}"
