"""The device kit's tables: ports, faults, commands, signals and error codes.

Each kind declares these once, each row citing its manual section.  The device runs from them
(a fault row carries its effect, a command row its handler, a signal row the signal it makes),
and ``devsim doc`` prints them, so what is documented is what runs.  The *declared points* of a
kind are in :mod:`devsim.core.points`, its parameters in :mod:`devsim.core.parameters`.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Mapping
from typing import Any, Generic, Literal, Protocol, TypeVar

import msgspec

from devsim.core.framing import Framing
from devsim.core.parameters import ParameterTable
from devsim.core.points import Point, PointType, UnknownName, ascii_digits, parse_bool
from devsim.core.signals import SignalBank, SignalKind

__all__ = [
    "CaptureTag",
    "Command",
    "Deviation",
    "DriveActions",
    "ErrorCode",
    "Fault",
    "FaultTable",
    "Homing",
    "Framing",
    "PortDef",
    "SignalDef",
    "SignalView",
    "Table",
    "declare_signals",
    "parse_port_default",
    "signal_points",
]

Effect = Literal["simulated", "stored"]
H = TypeVar("H")


#: The network schemes a port may declare as its default transport (:attr:`PortDef.default`).
DEFAULT_SCHEMES = ("udp", "tcp")


class CaptureTag(msgspec.Struct, frozen=True):
    """How a pcap capture tags a serial port's records (``--trace FILE.pcap``, the live capture):
    the devsim header's protocol and port bytes (:mod:`devsim.transports.pcap`, docs/wireshark.md:
    protocol 1 SERS, 2 GMS96, 3 POSELESTA, 4 IP247 PG, 5 PCD4.H3 serial S-Bus, 16 Modbus RTU, 0
    unknown; port 6, 7, 8 for POSELESTA's V6, V7, V8, else 0)."""

    protocol: int = 0
    port: int = 0

    def __post_init__(self) -> None:
        if not (0 <= self.protocol <= 255 and 0 <= self.port <= 255):
            raise ValueError(f"a capture tag's protocol and port are bytes, not {self.protocol}, {self.port}")


class PortDef(msgspec.Struct, frozen=True):
    """A port of a kind (``main`` by default; ``v6``, ``v7``, ``v8`` for the CNC).

    ``default`` declares where the port is served when nobody says otherwise: ``None`` (a serial
    port: a pty), or ``"udp:PORT"`` / ``"tcp:PORT"`` for a port the real device has on its
    Ethernet interface (``"udp:5050"`` for Ether-S-Bus).  ``devsim run`` serves such a port on
    that transport and number on loopback (``--port NAME=...`` overrides it); a plant file that
    gives the port no transport serves it on that scheme at an ephemeral port number
    (:attr:`default_transport`).

    ``framing`` declares how the port's byte stream is cut into messages, described and matched
    (:class:`~devsim.core.framing.Framing`): record and replay, the telegram tap and the monitor
    use it; ``None``: byte-exact, nothing decoded.

    ``hosts`` declares how many hosts the port serves at once over TCP: a serial port has one
    host (also when reached through a device server or RFC 2217); a port the real device has on
    its Ethernet interface may serve several (the PCD's Ether-S-Bus TCP port).  One more client is
    refused, or takes the place of an idle host (:mod:`devsim.transports.hosts`).

    ``capture`` declares the port a serial line for pcap captures (:class:`CaptureTag`): its
    records carry the devsim serial header (link type USER0) with these protocol and port bytes;
    ``None``: a port of the device's network interface, captured as IPv4/UDP.

    ``address`` declares where the device's address on a line shared with others (RS-485
    multidrop) comes from: the key of its configuration that holds it, dotted for a nested one
    (``"address"`` for the SERS's DIP switch 2, ``"dil.address"`` for the GMS96's DIL switch,
    ``"station"`` for an S-Bus station).  ``devsim run --drives`` sets it, and a plant file with
    two devices at one address on one bus is refused (:mod:`devsim.scenario.checks`).  ``None``:
    the port's protocol addresses no device, one device per line."""

    name: str = "main"
    doc: str = "the device's serial port"
    section: str = ""
    receive_only: bool = False
    default: str | None = None
    framing: Framing | None = None
    hosts: int = 1
    capture: CaptureTag | None = None
    address: str | None = None

    def __post_init__(self) -> None:
        if self.hosts < 1:
            raise ValueError(f"a port serves at least one host, not {self.hosts}")
        if self.default is not None:
            parse_port_default(self.default)

    def address_in(self, config: Mapping[str, Any]) -> Any:
        """The device's address in its configuration (parsed, defaults filled in), or ``None``
        where the port declares no address (or the configuration lacks it)."""
        value: Any = config
        for key in self.address.split(".") if self.address is not None else ():
            if not isinstance(value, Mapping) or key not in value:
                return None
            value = value[key]
        return None if self.address is None else value

    def addressed(self, config: Mapping[str, Any], address: int) -> dict[str, Any]:
        """``config`` with the device's address set to ``address`` (the port must declare one)."""
        if self.address is None:
            raise ValueError(f"port {self.name!r} declares no address")
        *outer, last = self.address.split(".")
        top = dict(config)
        level = top
        for key in outer:  # (copies of the nested mappings on the way: ``config`` stays as it was)
            inner = level.get(key)
            level[key] = dict(inner) if isinstance(inner, Mapping) else {}
            level = level[key]
        level[last] = address
        return top

    @property
    def default_transport(self) -> tuple[str, int] | None:
        """``(scheme, port)`` of the declared default (``("udp", 5050)``), or ``None``."""
        return None if self.default is None else parse_port_default(self.default)


def parse_port_default(text: str) -> tuple[str, int]:
    """``"udp:5050"`` → ``("udp", 5050)``; the scheme one of :data:`DEFAULT_SCHEMES`, the port
    1 … 65535."""
    scheme, sep, number = text.partition(":")
    if not sep or scheme not in DEFAULT_SCHEMES or not ascii_digits(number) or not 0 < int(number) <= 65535:
        raise ValueError(f"a port default is udp:PORT or tcp:PORT (PORT 1..65535), not {text!r}")
    return scheme, int(number)


MAIN_PORT = (PortDef(),)


class Fault(msgspec.Struct, frozen=True):
    """A fault a scenario, the control API (``fault`` op) or a fixture can switch on and off.

    ``apply(model, active)`` is its effect on the model."""

    name: str
    doc: str
    section: str
    apply: Callable[[Any, bool], None]


class FaultTable:
    """A kind's declared faults by name."""

    def __init__(self, faults: Iterable[Fault] = ()) -> None:
        self.faults: dict[str, Fault] = {}
        for fault in faults:
            if fault.name in self.faults:
                raise ValueError(f"fault {fault.name!r} declared twice")
            self.faults[fault.name] = fault

    def __iter__(self) -> Iterator[Fault]:
        return iter(self.faults.values())

    def __contains__(self, name: object) -> bool:
        return name in self.faults

    def names(self) -> list[str]:
        return list(self.faults)

    def apply(self, model: Any, name: str, active: Any, owner: str = "the device") -> None:
        fault = self.faults.get(name)
        if fault is None:
            known = ", ".join(self.faults) or "none"
            raise UnknownName(f"{owner} has no fault {name!r} (declared: {known})")
        fault.apply(model, parse_bool(active))


class Command(msgspec.Struct, Generic[H], frozen=True):
    """One row of a command table: the token (or statement type) a host sends, the handler
    that carries it out, the manual section, and whether it is simulated or only stored."""

    token: str
    handler: H
    section: str
    doc: str = ""
    effect: Effect = "simulated"
    #: The typed record the token's arguments arrive in, where a table has one per row (the
    #: control API's ops, :data:`devsim.runtime.ops.CONTROL`).
    request: Any = None


class Table(Generic[H]):
    """Token → :class:`Command`: the one dispatch idiom of every face."""

    def __init__(self, rows: Iterable[Command[H]]) -> None:
        self.rows: dict[str, Command[H]] = {}
        for row in rows:
            if row.token in self.rows:
                raise ValueError(f"command {row.token!r} declared twice")
            if not callable(row.handler):  # a row that only documents would not run
                raise TypeError(f"command {row.token!r} has no callable handler ({row.handler!r})")
            self.rows[row.token] = row

    def __iter__(self) -> Iterator[Command[H]]:
        return iter(self.rows.values())

    def __contains__(self, token: object) -> bool:
        return token in self.rows

    def get(self, token: str) -> H | None:
        row = self.rows.get(token)
        return None if row is None else row.handler

    def __getitem__(self, token: str) -> H:
        return self.rows[token].handler



class ErrorCode(msgspec.Struct, frozen=True):
    """An error (or status) code the device answers with, and its text."""

    code: str
    text: str
    section: str = ""


class Deviation(msgspec.Struct, frozen=True):
    """One place where the simulator knowingly differs from what its manual says a host or the
    machine side can observe, and why (a pty cannot carry 7-bit parity, for example).

    Everything else the manual states is meant to hold; ``devsim doc`` prints these rows as the
    kind's *Deviations* section."""

    section: str  # the manual section, e.g. "§2.6.1.2"
    manual: str  # what the manual says (in English)
    simulator: str  # what the simulator does instead
    reason: str  # why it does


class SignalDef(msgspec.Struct, frozen=True):
    """A digital input, output or analog quantity: makes the signal and its point."""

    name: str
    kind: SignalKind
    initial: Any
    doc: str
    section: str = ""
    unit: str = ""
    type: PointType | None = None  # default: bool for inputs/outputs, float for quantities
    minimum: float | None = None
    maximum: float | None = None
    choices: tuple[Any, ...] | None = None

    @property
    def point_type(self) -> PointType:
        if self.type is not None:
            return self.type
        return "float" if self.kind == "quantity" else "bool"


def declare_signals(bank: SignalBank, defs: Iterable[SignalDef]) -> None:
    """Define every declared signal in a device's bank (in one step: banks that declare the same
    signals share their names and positions)."""
    bank.declare((d.name, d.kind, d.initial, d.doc) for d in defs)


class SignalView(Protocol):
    """What :func:`signal_points` reads and writes: a :class:`SignalBank`, or a view of it (a
    kind may show its outputs through one, e.g. all L while their relay supply is lost)."""

    def get(self, name: str) -> Any: ...
    def set(self, name: str, value: Any) -> Any: ...


def signal_points(
    defs: Iterable[SignalDef], bank: Callable[[Any], SignalView] = lambda m: m.signals
) -> list[Point]:
    """``input.*`` and ``quantity.*`` settable, ``output.*`` read-only, all in ``state``."""
    points = []
    for d in defs:
        name = f"{d.kind}.{d.name}"

        def get(model: Any, key: str = d.name) -> Any:
            return bank(model).get(key)

        def put(model: Any, value: Any, key: str = d.name) -> None:
            bank(model).set(key, value)

        points.append(
            Point(
                name,
                d.point_type,
                d.doc,
                d.section,
                d.unit,
                get=get,
                put=None if d.kind == "output" else put,
                minimum=d.minimum,
                maximum=d.maximum,
                choices=d.choices,
                in_state=True,
                shared=True,
            )
        )
    return points


class Reference(msgspec.Struct):
    """What ``devsim doc KIND`` prints, gathered from a kind's tables."""

    commands: list[Command[Any]] = msgspec.field(default_factory=list)
    errors: list[ErrorCode] = msgspec.field(default_factory=list)
    #: The kind's parameters as kit rows (:mod:`devsim.core.parameters`), printed with their key,
    #: aliases, range, default and effect.
    parameter_table: ParameterTable | None = None
    #: Where the simulator knowingly differs from its manual, and why.
    deviations: list[Deviation] = msgspec.field(default_factory=list)


class DriveActions(msgspec.Struct, frozen=True):
    """What a kind's model does as a drive (one axis), for drive-profile facades such as CiA 402
    (:mod:`devsim.facades.cia402`): the kind declares it as ``Device.drive``; positions in the
    units of its ``axis.position``, speeds in those units per second."""

    enable: Callable[[Any, bool], None]  # power stage on (operation enabled) / off
    move_to: Callable[[Any, float, float], None]  # absolute target, speed (axis units, units/s)
    jog: Callable[[Any, float], None]  # run at a velocity (units/s); 0 stops with the ramp
    quick_stop: Callable[[Any], None]
    reset_fault: Callable[[Any], None]
    position: Callable[[Any], float]
    velocity: Callable[[Any], float]
    enabled: Callable[[Any], bool]
    fault: Callable[[Any], bool]
    moving: Callable[[Any], bool]
    following_error: Callable[[Any], float] = lambda m: 0.0
    #: The kind's own reference run as CiA 402 homing mode (6060h = 6); ``None``: the device has
    #: no reference run of its own, so the mode is not supported.
    homing: Homing | None = None


class Homing(msgspec.Struct, frozen=True):
    """A kind's own reference run as a drive profile's homing (CiA 402 homing mode,
    :mod:`devsim.facades.cia402_homing`).  ``methods``: a row per homing method number (6098h,
    CiA 402-2) the reference run performs, its handler starting that run on the model with
    (speed during search for switch, speed during search for zero, acceleration) in the drive's
    units (6099h sub 1, 2 and 609Ah; 0: the device's own parameter), raising
    :class:`~devsim.core.points.BadValue` where the device refuses; each row cites the manual
    section of the run.  ``state``: ``"running"`` while a reference run is under way, else
    ``"attained"`` when the device has its reference point, ``"failed"`` when it has none."""

    methods: Table[Callable[[Any, float, float, float], None]]
    state: Callable[[Any], str]
