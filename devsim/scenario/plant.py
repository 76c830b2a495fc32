"""Building a plant: the devices of a plant (or scenario) file, each served on its port.

:func:`build_plant` runs inside a runtime's loop; :func:`start_plant` starts a runtime in a
background thread and builds the plant there (what ``devsim up``, the pytest plugin and tests
use).  Devices on a ``bus`` share that bus's port (RS-485 multidrop).
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from devsim.core.device import Device
from devsim.core.runtime import Runtime
from devsim.scenario.schema import PlantSpec, TransportSpec

__all__ = ["Plant", "build_plant", "make_transport", "plant_running", "start_plant"]


def make_transport(spec: TransportSpec) -> Any:
    """A transport object for a pty, tcp or rfc2217 transport spec."""
    from devsim.transports.pty import PtyTransport
    from devsim.transports.rfc2217 import Rfc2217Transport
    from devsim.transports.tcp import TcpTransport

    if spec.pty is not None:
        return PtyTransport(link=spec.pty.link)
    if spec.tcp is not None:
        return TcpTransport(spec.tcp.host, spec.tcp.port)
    if spec.rfc2217 is not None:
        return Rfc2217Transport(spec.rfc2217.host, spec.rfc2217.port)
    raise ValueError("a bus member has no transport of its own")


@dataclass
class Plant:
    """A running plant: its runtime, devices, and per port the transport and the line."""

    runtime: Runtime
    spec: PlantSpec
    devices: dict[str, Device] = field(default_factory=dict)
    transports: dict[str, Any] = field(default_factory=dict)  # port name -> transport
    lines: dict[str, Any] = field(default_factory=dict)  # port name -> Line
    kinds: dict[str, str] = field(default_factory=dict)  # port name -> "pty" | "tcp" | "rfc2217"

    def port(self, name: str) -> str:
        """What a host opens for port ``name`` (a device or bus): pty path or URL."""
        transport = self.transports[name]
        return str(getattr(transport, "url", "") or transport.address)

    def path(self, name: str) -> str:
        """The pty path (or the host:port address) of port ``name``."""
        return str(self.transports[name].address)

    def port_of(self, device: str) -> str:
        """The port name a device is reached through (its own, or its bus)."""
        for spec in self.spec.devices:
            if spec.name == device:
                return spec.transport.bus or spec.name
        raise KeyError(device)

    def describe(self) -> list[str]:
        """One line per port, as ``devsim up`` prints them."""
        rows = []
        for name in self.transports:
            members = [d.name for d in self.spec.devices if (d.transport.bus or d.name) == name]
            who = name if members == [name] else f"{name} ({', '.join(members)})"
            rows.append(f"{who}: {self.kinds[name]} {self.port(name)}")
        return rows


async def build_plant(runtime: Runtime, spec: PlantSpec, *, trace_dir: str | Path | None = None) -> Plant:
    """Create the devices of ``spec`` in ``runtime`` (running in this loop) and serve them."""
    plant = Plant(runtime, spec)
    if trace_dir is not None:
        Path(trace_dir).mkdir(parents=True, exist_ok=True)
    for dev in spec.devices:
        device = runtime.add_device(dev.kind, dev.name, dev.device_config())
        plant.devices[dev.name] = device
    groups: dict[str, tuple[TransportSpec, list[Device]]] = {}
    for dev in spec.devices:
        if dev.transport.bus is None:
            groups[dev.name] = (dev.transport, [plant.devices[dev.name]])
    for bus in spec.buses:
        members = [plant.devices[d.name] for d in spec.devices if d.transport.bus == bus.name]
        if members:
            groups[bus.name] = (bus.transport, members)
    for port, (tspec, members) in groups.items():
        transport = make_transport(tspec)
        trace = Path(trace_dir) / f"{port}.trace" if trace_dir is not None else None
        line = await runtime.serve(members if len(members) > 1 else members[0], transport, trace=trace)
        plant.transports[port] = transport
        plant.lines[port] = line
        plant.kinds[port] = tspec.kind
    for dev in spec.devices:
        if dev.state:
            plant.devices[dev.name].apply_state(dev.state)
    return plant


def start_plant(
    spec: PlantSpec,
    *,
    virtual: bool = False,
    speed: float = 1.0,
    state_dir: str | Path | None = None,
    trace_dir: str | Path | None = None,
) -> Plant:
    """Start a runtime in a background thread and build ``spec`` in it; stop with
    ``plant.runtime.stop()``."""
    runtime = Runtime(virtual=virtual, speed=speed, state_dir=state_dir).start()
    try:
        return runtime.run(build_plant(runtime, spec, trace_dir=trace_dir))
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
