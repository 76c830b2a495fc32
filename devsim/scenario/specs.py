"""The plant file's building blocks for one device (spec pieces shared by plants and scenarios):
durations, the transport a port is served on, and the fieldbus and IT facades (Modbus, CANopen,
MQTT, OPC UA) a device or plant adds.  :mod:`devsim.scenario.schema` puts them together.

Declared as typed data (:class:`devsim.core.typed.Typed`, msgspec structs)."""

from __future__ import annotations

import math
import re
from typing import Annotated, Any, Literal, Self

from msgspec import Meta

from devsim.core.typed import Typed, doc

__all__ = [
    "Between",
    "CanopenSpec",
    "Duration",
    "ModbusSpec",
    "MqttSpec",
    "OpcuaSpec",
    "PtySpec",
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


class Duration(float):
    """Seconds, given as a number or as text like ``2s``, ``150ms``, ``1.5 min``."""

    @classmethod
    def from_data(cls, value: Any) -> Duration:
        return cls(parse_duration(value, "{field}"))


class PositiveDuration(Duration):
    """A duration above zero."""

    #: What a duration not above zero is refused with.
    refusal = "Input should be greater than 0"

    @classmethod
    def from_data(cls, value: Any) -> Self:
        seconds = parse_duration(value, "{field}")
        if not seconds > 0:
            raise ValueError(cls.refusal)
        return cls(seconds)


class Rate(PositiveDuration):
    """How often something is sampled: a positive duration."""

    refusal = "`{field}` must be a positive duration like 1s or 500ms"


class Between(tuple[float, float]):
    """Two durations ``[earliest, latest]`` since the start."""

    @classmethod
    def from_data(cls, value: Any) -> Between:
        if not isinstance(value, list | tuple) or len(value) != 2:
            raise ValueError("`between` must be two durations like [1s, 1.5s]")
        low, high = (parse_duration(v, "between") for v in value)
        if low > high:
            raise ValueError("`between` must go from the earlier to the later time")
        return cls((low, high))


class MqttUrl(str):
    """``mqtt://HOST[:PORT]`` of a broker."""

    @classmethod
    def from_data(cls, value: Any) -> MqttUrl:
        if not isinstance(value, str):
            raise ValueError("Input should be a valid string")
        from devsim.facades.mqtt_topics import parse_url

        parse_url(value)
        return cls(value)

    @property
    def address(self) -> tuple[str, int]:
        """The broker's host and port."""
        from devsim.facades.mqtt_topics import parse_url

        return parse_url(self)


# -- ports and facades ----------------------------------------------------------------------
class PtySpec(Typed):
    link: Annotated[str, Meta(min_length=1), doc("a path for a symlink to the pty")] | None = None


class TcpSpec(Typed):
    port: Annotated[int, Meta(ge=0, le=65535)] = 0
    host: str = "127.0.0.1"

    def __post_init__(self) -> None:
        _check_host(self.host)


def _check_host(host: str) -> None:
    """A host that cannot be looked up at all is refused with the file (it was a UnicodeError's
    traceback when devsim up opened it)."""
    from devsim.runtime.control import host_problem

    problem = host_problem(host)
    if problem is not None:
        raise ValueError(problem)


_TRANSPORTS = ("pty", "tcp", "rfc2217", "udp", "bus")


class TransportSpec(Typed):
    """Exactly one of ``pty``, ``tcp``, ``rfc2217``, ``udp`` or ``bus`` (the name of a bus)."""

    pty: PtySpec | None = None
    tcp: TcpSpec | None = None
    rfc2217: TcpSpec | None = None
    udp: TcpSpec | None = None
    bus: str | None = None

    def __post_init__(self) -> None:
        given = [k for k in _TRANSPORTS if getattr(self, k) is not None]
        if len(given) > 1:
            raise ValueError(f"give one transport, not {' and '.join(given)}")
        if not given:
            self.pty = PtySpec()

    @property
    def kind(self) -> str:
        return next(k for k in _TRANSPORTS if getattr(self, k) is not None)


class ModbusSpec(Typed):
    """The device also on Modbus (issue 13): ``{tcp: {port: 5020}}`` (Modbus TCP) or ``{rtu: {}}``
    (Modbus RTU on a pty, ``{rtu: {link: /tmp/ttyMB}}`` with a symlink); ``unit`` its unit id,
    ``line`` the RTU line settings (``19200 8E1``);
    ``map`` overrides entries of the generated register map (``{name: {address, table, scale}}``
    or ``{name: null}``)."""

    tcp: TcpSpec | None = None
    rtu: PtySpec | None = None
    unit: Annotated[Annotated[int, Meta(ge=1, le=247)] | None, doc(
        "the unit id; none: 1, or with layout mirror the kind's own (PCD4.H3: its S-Bus station, spec §9.8)")] = None
    line: Annotated[str, doc("RTU line settings")] = "19200 8E1"
    layout: Annotated[Literal["points", "mirror"], doc(
        "the map: generated from the points, or the kind's own mirror (PCD4.H3: its media, spec §9.8)")] = "points"
    map: dict[str, Any] = {}

    def __post_init__(self) -> None:
        if (self.tcp is None) == (self.rtu is None):
            raise ValueError("give tcp or rtu")
        from devsim.core.device import SerialSettings

        SerialSettings.parse(self.line)  # refused with the file, not when the line opens

    def spec(self) -> str:
        """The ``--modbus`` form: ``tcp:HOST:PORT``, ``rtu`` or ``rtu:LINK``."""
        if self.tcp is not None:
            return f"tcp:{self.tcp.host}:{self.tcp.port}"
        assert self.rtu is not None
        return f"rtu:{self.rtu.link}" if self.rtu.link else "rtu"


class CanopenSpec(Typed):
    """A device as a CANopen node (issue 13): its node id and the CAN network it joins, a
    socketcand server at ``[HOST:]PORT`` (the plant's devices with the same network share one bus)
    or ``socketcan:CHANNEL``."""

    node: Annotated[int, Meta(ge=1, le=127), doc("the node id")]
    network: Annotated[str, Meta(pattern=r"^(socketcan:\S+|(\S+:)?\d+)$"), doc(
        "[HOST:]PORT of a socketcand server, or socketcan:CHANNEL")] = "127.0.0.1:29536"

    def __post_init__(self) -> None:
        if self.server is not None:
            host, port = self.server
            _check_host(host)
            if port > 65535:  # (OverflowError's traceback from the bind in devsim up)
                raise ValueError(f"the socketcand port is 0 … 65535, not {port}")

    @property
    def server(self) -> tuple[str, int] | None:
        """The socketcand server's host and port (``None`` on a SocketCAN channel)."""
        if self.network.startswith("socketcan:"):
            return None
        host, _, port = self.network.rpartition(":")
        return host or "127.0.0.1", int(port)


class MqttSpec(Typed):
    """The plant's devices also over MQTT (issue 14, :mod:`devsim.facades.mqtt`): ``url``
    ``mqtt://HOST[:PORT]`` of the broker (none: an embedded broker on loopback), ``convention``
    ``devsim`` or ``sparkplug``, ``rate`` how often the points are sampled for changes (device
    time), ``plant`` the plant's name in the topics (default: the plant's ``name``),
    ``primary_host`` the Sparkplug Primary Host Application id whose STATE the births wait for."""

    url: MqttUrl | None = None
    convention: Literal["devsim", "sparkplug"] = "devsim"
    rate: Annotated[Rate, doc("seconds (or a duration like 500ms) between samples")] = Rate(1.0)
    plant: str | None = None
    primary_host: Annotated[str | None, doc(
        "sparkplug: the Primary Host Application id; births only while spBv1.0/STATE/<id> is online")] = None

    def __post_init__(self) -> None:
        if self.primary_host is not None:
            from devsim.facades.mqtt_topics import check_name

            check_name("primary host", self.primary_host)
            if self.convention != "sparkplug":
                raise ValueError("primary_host is a Sparkplug host application: only with convention: sparkplug")


class OpcuaSpec(Typed):
    """The plant's devices on one OPC UA server (issue 14, :mod:`devsim.facades.opcua`):
    ``opcua: {}`` serves ``opc.tcp://127.0.0.1:4840/devsim/``; ``port: 0`` takes a free port;
    ``period`` is how often the points are sampled for subscriptions (device time)."""

    host: str = "127.0.0.1"
    port: Annotated[int, Meta(ge=0, le=65535)] = 4840
    period: Annotated[PositiveDuration, doc("sampling period for subscriptions, e.g. 100ms")] = PositiveDuration(0.1)

    def __post_init__(self) -> None:
        _check_host(self.host)

    def spec(self) -> str:
        """The ``--opcua`` form: ``HOST:PORT``."""
        return f"[{self.host}]:{self.port}" if ":" in self.host else f"{self.host}:{self.port}"
