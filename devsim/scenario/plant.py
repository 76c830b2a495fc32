"""Building a plant: the devices of a plant (or scenario) file, each served on its port.

:func:`build_plant` runs inside a runtime's loop; :func:`start_plant` starts a runtime in a
background thread and builds the plant there (what ``devsim up``, the pytest plugin and tests
use).  Devices on a ``bus`` share that bus's port (RS-485 multidrop), each by its first port.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Literal

import msgspec

from devsim.core.device import Device
from devsim.core.points import BadValue
from devsim.runtime import Runtime, port_key
from devsim.scenario.schema import PlantSpec, TransportSpec
from devsim.transports.fdlimit import is_out_of_fds, port_budget

__all__ = ["Plant", "StateRefused", "TraceFormat", "build_plant", "make_transport", "plant_running", "start_plant"]

#: How ``trace_dir`` traces are written: text (``NAME.trace``) or pcap (``NAME.pcap``).
TraceFormat = Literal["text", "pcap"]
_TRACE_SUFFIX = {"text": "trace", "pcap": "pcap"}


class StateRefused(ValueError):
    """A device refused a value of its ``state:`` that the file's check took: the point's type
    fits, the device's own rule does not (a program's text beyond the formats in force).
    ``str()`` is ``devices.N.state.NAME: message``, N counted from 1 as the file's check counts."""


def make_transport(spec: TransportSpec) -> Any:
    """A transport object for a pty, tcp, rfc2217 or udp transport spec."""
    from devsim.transports.pty import PtyTransport
    from devsim.transports.rfc2217 import Rfc2217Transport
    from devsim.transports.tcp import TcpTransport
    from devsim.transports.udp import UdpTransport

    if spec.pty is not None:
        return PtyTransport(link=spec.pty.link)
    if spec.tcp is not None:
        return TcpTransport(spec.tcp.host, spec.tcp.port)
    if spec.rfc2217 is not None:
        return Rfc2217Transport(spec.rfc2217.host, spec.rfc2217.port)
    if spec.udp is not None:
        return UdpTransport(spec.udp.host, spec.udp.port)
    raise ValueError("a bus member has no transport of its own")


class Plant(msgspec.Struct):
    """A running plant: its runtime, devices, and per port the transport and the line."""

    runtime: Runtime
    spec: PlantSpec
    devices: dict[str, Device] = msgspec.field(default_factory=dict)
    transports: dict[str, Any] = msgspec.field(default_factory=dict)  # port name -> transport
    lines: dict[str, Any] = msgspec.field(default_factory=dict)  # port name -> Line
    kinds: dict[str, str] = msgspec.field(default_factory=dict)  # port name -> "pty" | "tcp" | "rfc2217" | "udp" | ""
    refused: dict[str, str] = msgspec.field(default_factory=dict)  # port name -> why it is not served
    facades: list[str] = msgspec.field(default_factory=list)  # "NAME.canopen: ...", MQTT: lines devsim up prints

    def port(self, name: str) -> str:
        """What a host opens for port ``name`` (a device or bus): pty path or URL."""
        transport = self.transports[name]
        return str(getattr(transport, "url", "") or transport.address)

    def path(self, name: str) -> str:
        """The pty path (or the host:port address) of port ``name``."""
        return str(self.transports[name].address)

    def port_of(self, device: str, port: str | None = None) -> str:
        """The plant port a device's serial port (default: its first) is reached through: its
        own (``DEVICE`` or ``DEVICE.PORT``), or its bus."""
        for spec in self.spec.devices:
            if spec.name == device:
                port = port or spec.port_names()[0]
                return spec.transport_of(port).bus or port_key(device, port)
        raise KeyError(device)

    def describe(self) -> list[str]:
        """One line per port, as ``devsim up`` prints them."""
        rows = []
        on_bus: dict[str, list[str]] = {}
        for device in self.spec.devices:
            bus = device.bus()
            if bus is not None:
                on_bus.setdefault(bus, []).append(device.name)
        for name in self.transports:
            members = on_bus.get(name, [])
            who = f"{name} ({', '.join(members)})" if members else name
            kind = self.kinds[name]  # (none for the OPC UA server: its URL says it, as devsim run prints it)
            rows.append(f"{who}: {kind} {self.port(name)}" if kind else f"{who}: {self.port(name)}")
        return rows + self.facades


async def build_plant(
    runtime: Runtime,
    spec: PlantSpec,
    *,
    trace_dir: str | Path | None = None,
    keep_going: bool = False,
    trace_format: TraceFormat = "text",
    control: bool = True,
) -> Plant:
    """Create the devices of ``spec`` in ``runtime`` (running in this loop) and serve them.

    With ``trace_dir`` every port's traffic is traced there, as ``NAME.trace`` (text) or, with
    ``trace_format="pcap"``, as ``NAME.pcap`` (:mod:`devsim.transports.pcap`).

    With ``keep_going`` a port that cannot be opened because the process is out of file
    descriptors is left out (listed in ``plant.refused``) and the others are served; so is a port
    beyond the descriptors' budget (:func:`devsim.transports.fdlimit.port_budget`, which keeps the
    control clients' share unless ``control`` is false: no control server)."""
    plant = Plant(runtime, spec)
    if trace_dir is not None:
        Path(trace_dir).mkdir(parents=True, exist_ok=True)
    for dev in spec.devices:
        device = runtime.add_device(dev.kind, dev.name, dev.device_config())
        plant.devices[dev.name] = device
    groups: dict[str, tuple[TransportSpec, list[Device], str]] = {}
    for name, dev, port in spec.device_ports():
        groups[name] = (dev.transport_of(port), [plant.devices[dev.name]], port)
    for bus in spec.buses:
        on_bus = [d for d in spec.devices if d.bus() == bus.name]
        if on_bus:  # (each on the bus by its first port, of one name: plant_problems)
            groups[bus.name] = (bus.transport, [plant.devices[d.name] for d in on_bus], on_bus[0].port_names()[0])
    budget = port_budget(control=control) if keep_going else len(groups)
    for name, (tspec, members, port) in groups.items():
        if budget <= 0:
            plant.refused[name] = "not enough file descriptors left"
            continue
        budget -= 1
        transport = make_transport(tspec)
        trace = Path(trace_dir) / f"{name}.{_TRACE_SUFFIX[trace_format]}" if trace_dir is not None else None
        try:
            line = await runtime.serve(members, transport, port=port, trace=trace)
        except OSError as exc:
            if not (keep_going and is_out_of_fds(exc)):
                raise
            plant.refused[name] = exc.strerror or str(exc)
            continue
        plant.transports[name] = transport
        plant.lines[name] = line
        plant.kinds[name] = tspec.kind
    for dev in spec.devices:
        if dev.modbus is not None:
            await _serve_modbus(plant, dev, trace_dir, trace_format)
    await _serve_canopen(plant)
    for index, dev in enumerate(spec.devices):
        if dev.state:
            try:
                plant.devices[dev.name].apply_state(dev.state)
            except BadValue as exc:  # the device refused a value its point's type took (the file's check)
                raise StateRefused(f"devices.{index + 1}.state.{exc}") from None  # (counted from 1, as check counts)
    if spec.mqtt is not None:
        await _serve_mqtt(plant)
    if spec.opcua is not None:
        await _serve_opcua(plant)
    return plant


async def _serve_canopen(plant: Plant) -> None:
    """The devices' CANopen nodes, one CAN network per ``canopen.network`` (``NAME.canopen``)."""
    networks: dict[str, list[tuple[Device, int]]] = {}
    for dev in plant.spec.devices:
        if dev.canopen is not None:
            networks.setdefault(dev.canopen.network, []).append((plant.devices[dev.name], dev.canopen.node))
    if not networks:
        return
    from devsim.facades.canopen_node import serve_nodes

    for where, nodes in networks.items():
        plant.facades += await serve_nodes(plant.runtime, nodes, where)


async def _serve_mqtt(plant: Plant) -> None:
    """The plant's devices over MQTT (the plant file's ``mqtt:`` section)."""
    from devsim.facades.mqtt import start_mqtt

    mqtt = plant.spec.mqtt
    assert mqtt is not None
    plant.facades += await start_mqtt(plant.runtime, list(plant.devices.values()), mqtt.url,
                                      plant=mqtt.plant or plant.spec.name or "plant",
                                      convention=mqtt.convention, rate=mqtt.rate, primary_host=mqtt.primary_host)


async def _serve_modbus(plant: Plant, dev: Any, trace_dir: str | Path | None, trace_format: TraceFormat) -> None:
    """A device's Modbus facade (``NAME.modbus``): TCP through pymodbus's server, RTU on a pty."""
    from devsim.facades.modbus import start_modbus

    name = f"{dev.name}.modbus"
    trace = str(Path(trace_dir) / f"{name}.{_TRACE_SUFFIX[trace_format]}") if trace_dir is not None else None
    where, transport = await start_modbus(plant.runtime, plant.devices[dev.name], dev.modbus.spec(),
                                          unit=dev.modbus.unit, overrides=dev.modbus.map, trace=trace,
                                          line=dev.modbus.line, layout=dev.modbus.layout)
    if transport is None:
        plant.transports[name] = _Address(f"socket://{where}", where)
        plant.kinds[name] = "tcp"
    else:
        plant.transports[name] = transport
        plant.lines[name] = plant.runtime.lines[name]
        plant.kinds[name] = "pty"


async def _serve_opcua(plant: Plant) -> None:
    """The plant's OPC UA server (port ``opcua``): every device under Objects."""
    from devsim.facades.opcua import start_opcua

    opcua = plant.spec.opcua
    assert opcua is not None
    facade = await start_opcua(plant.runtime, list(plant.devices.values()), opcua.spec(), period=opcua.period,
                               name=plant.spec.name or "devsim")
    plant.transports["opcua"] = _Address(facade.url, facade.url)
    plant.kinds["opcua"] = ""


class _Address(msgspec.Struct, frozen=True):
    """Where a server the plant does not own as a transport listens (the Modbus TCP facade)."""

    url: str
    address: str


def start_plant(
    spec: PlantSpec,
    *,
    virtual: bool = False,
    speed: float = 1.0,
    state_dir: str | Path | None = None,
    trace_dir: str | Path | None = None,
    trace_format: TraceFormat = "text",
    idle_drop: float | None = None,
) -> Plant:
    """Start a runtime in a background thread and build ``spec`` in it; stop with
    ``plant.runtime.stop()``.  ``idle_drop``: as ``devsim up --idle-drop``."""
    runtime = Runtime(virtual=virtual, speed=speed, state_dir=state_dir)
    runtime.idle_drop = idle_drop
    runtime.start()
    try:
        return runtime.run(build_plant(runtime, spec, trace_dir=trace_dir, trace_format=trace_format))
    except BaseException:
        runtime.stop()
        raise


@contextmanager
def plant_running(spec: PlantSpec, **kwargs: Any) -> Iterator[Plant]:
    """``with plant_running(spec, virtual=True) as plant: ...`` – stopped afterwards."""
    plant = start_plant(spec, **kwargs)
    try:
        yield plant
    finally:
        plant.runtime.stop()
