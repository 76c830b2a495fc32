"""The pytest plugin: simulated devices, plants and scenarios as test fixtures.

Registered through the ``pytest11`` entry point (``devsim = "devsim.pytest_plugin"``), so it is
active wherever ``devsim-motion`` is installed.  It provides:

``devsim_device``
    A factory ``make(kind, config=None, *, transport="pty", virtual=True, name=None,
    state_dir=None, boot=True)`` returning a :class:`SimDevice`: one device served on a real pty
    (or TCP / RFC 2217 port), in its own :class:`~devsim.runtime.Runtime` (a background
    thread), with the control API and the clock.  Every device made is stopped at teardown.

``devsim_plant``
    A factory ``make(path_or_dict, *, virtual=True, state_dir=None, boot=True)`` returning a
    running :class:`SimPlant` (a :class:`~devsim.scenario.plant.Plant` with control helpers)
    built from a plant or scenario file, or from a dict.  Stopped at teardown.

``@pytest.mark.devsim_scenario(path_or_dict, mode=None, check=True)``
    Runs the scenario before the test body; the test fails with the scenario report when the
    scenario fails (unless ``check=False``).  The result is the ``devsim_scenario_result``
    fixture.

``scenario_*.yaml`` / ``scenario_*.yml`` files
    Collected as test items (one per file) and run in the scenario's own time mode; a failure
    shows the scenario report.  Turn off with the ini option ``devsim_collect_scenarios = false``.

The fixtures are synchronous and work the same in ``async def`` tests (pytest-asyncio): the
simulator runs in its own thread and event loop, never in the test's loop.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import Any

import msgspec
import pytest

from devsim.core.clock import VirtualClock
from devsim.core.device import Device
from devsim.runtime import Runtime
from devsim.runtime import requests as rq
from devsim.runtime.ops import run

__all__ = [
    "DeviceFactory",
    "PlantFactory",
    "ScenarioFailed",
    "SimDevice",
    "run_scenario_spec",
]

#: Longest boot the factories wait for (simulated seconds, or real seconds on a real clock).
BOOT_TIMEOUT = 60.0


# -- helpers -------------------------------------------------------------------------------
def _transport_spec(transport: str | Mapping[str, Any]) -> Any:
    """``"pty"``, ``"tcp"``, ``"rfc2217"``, ``"udp"`` or a plant-file transport mapping → TransportSpec."""
    from devsim.scenario.schema import TransportSpec

    if isinstance(transport, str):
        if transport not in ("pty", "tcp", "rfc2217", "udp"):
            raise ValueError(f"transport must be 'pty', 'tcp', 'rfc2217', 'udp' or a mapping, not {transport!r}")
        spec = TransportSpec.parse({transport: {}})
    else:
        spec = TransportSpec.parse(dict(transport))
    if spec.bus is not None:
        raise ValueError("devsim_device serves one device on its own port; use devsim_plant for buses")
    return spec


def _wait_booted(runtime: Runtime, devices: list[Device]) -> None:
    """Virtual time: jump past the boot of ``devices``; real time: wait for it."""

    def booted() -> bool:
        return not any(device.booting for device in devices)

    if isinstance(runtime.clock, VirtualClock):
        if not runtime.run_until(booted, BOOT_TIMEOUT):
            raise RuntimeError("the device did not finish booting")
        return
    done = threading.Event()

    def check() -> None:
        if booted():
            done.set()

    undo = runtime.call(lambda: [device.on_ready(check) for device in devices])
    try:
        if not done.wait(BOOT_TIMEOUT):
            raise RuntimeError("the device did not finish booting")
    finally:
        runtime.call(lambda: [u() for u in undo])


def _resolve(path: str | os.PathLike[str], *bases: Path) -> Path:
    """A relative path is looked up next to the test file first, then in the given bases."""
    candidate = Path(path)
    if candidate.is_absolute():
        return candidate
    for base in bases:
        if (base / candidate).exists():
            return base / candidate
    return candidate


class _SerialPorts:
    """pyserial ports opened through :meth:`SimDevice.open_serial`, closed at teardown."""

    def __init__(self) -> None:
        self.ports: list[Any] = []

    def close(self) -> None:
        while self.ports:
            port = self.ports.pop()
            try:
                port.close()
            except Exception:  # noqa: BLE001 - closing what a test may have closed already
                pass


# -- one device ------------------------------------------------------------------------------
class SimDevice:
    """One simulated device on its port, with the control API and the clock.

    ``port`` is what a host opens: the pty path (or its link) for a pty, the ``socket://`` or
    ``rfc2217://`` URL for TCP and RFC 2217 (``serial.serial_for_url(device.port)`` works for
    all three); ``url`` is the same for network ports and the path for a pty; ``address`` is the
    pty path or ``host:port``.  All control methods are thread-safe.
    """

    def __init__(
        self,
        runtime: Runtime,
        name: str,
        kind: str,
        transport: Any,
        transport_kind: str,
        transports: Mapping[str, Any] | None = None,
    ) -> None:
        self.runtime = runtime
        self.name = name
        self.kind = kind
        self.transport = transport
        self.transport_kind = transport_kind
        #: Every served serial port of the device by port name (the first is ``transport``).
        self.transports: dict[str, Any] = dict(transports or {})
        self._serial = _SerialPorts()
        self._owns_runtime = True

    def __repr__(self) -> str:
        return f"<SimDevice {self.name} ({self.kind}) on {self.transport_kind} {self.port}>"

    # -- where the host connects ---------------------------------------------------------------
    @property
    def url(self) -> str:
        return str(getattr(self.transport, "url", "") or self.transport.address)

    @property
    def port(self) -> str:
        return self.url

    @property
    def address(self) -> str:
        return str(self.transport.address)

    def port_url(self, port: str) -> str:
        """What a host opens for one serial port of a device with several (``devsim doc KIND``
        lists them)."""
        transport = self.transports[port]
        return str(getattr(transport, "url", "") or transport.address)

    @property
    def device(self) -> Device:
        """The device object itself (touch it only in the runtime's thread, e.g. in
        :meth:`run_until` predicates or through ``runtime.call``)."""
        return self.runtime.device(self.name)

    @property
    def serial_settings(self) -> Any:
        return self.device.serial_settings

    def open_serial(self, **kwargs: Any) -> Any:
        """A pyserial port on this device at its configured line settings (closed at teardown
        if the test has not closed it)."""
        import serial

        settings = self.serial_settings
        options: dict[str, Any] = {
            "baudrate": settings.baudrate,
            "bytesize": settings.bytesize,
            "parity": settings.parity,
            "stopbits": settings.stopbits,
            "timeout": 2.0,
        }
        options.update(kwargs)
        port = serial.serial_for_url(self.port, **options)
        self._serial.ports.append(port)
        return port

    # -- control API (the ops of devsim.runtime.ops.CONTROL, on this device) ---------------------
    def read(self, name: str) -> Any:
        return run(self.runtime, rq.Read(self.name, name))

    def set(self, name: str, value: Any) -> None:
        run(self.runtime, rq.Set(self.name, name, value))

    def state(self) -> dict[str, Any]:
        result: dict[str, Any] = run(self.runtime, rq.State(self.name))
        return result

    def names(self) -> list[str]:
        """The device's declared control names."""
        return [row["name"] for row in run(self.runtime, rq.Names(self.name))]

    def fault(self, kind: str, active: bool = True) -> None:
        """Switch a fault the device's kind declares (``devsim doc KIND``) on or off."""
        run(self.runtime, rq.SwitchFault(self.name, kind, active))

    def line_fault(self, kind: str, active: bool = True, *, port: str = "main", **params: Any) -> None:
        """Start or end a fault on the device's line (``corrupt``, ``noise`` with ``rate`` ...)."""
        run(self.runtime, rq.LineFault(self.name, kind, active, port, params))

    def power_cycle(self, wipe: bool = False, *, boot: bool = True) -> None:
        """Switch off and on; with ``boot`` (and virtual time) run past the boot again."""
        run(self.runtime, rq.PowerCycle(self.name, wipe))
        if boot:
            self.wait_booted()

    def wait_booted(self) -> None:
        _wait_booted(self.runtime, [self.device])

    # -- the clock -------------------------------------------------------------------------------
    @property
    def virtual(self) -> bool:
        return isinstance(self.runtime.clock, VirtualClock)

    def now(self) -> float:
        return self.runtime.now()

    def advance(self, seconds: float) -> float:
        """Move virtual time on by ``seconds``; returns the new time."""
        return self.runtime.advance(seconds)

    def run_until(self, predicate: Callable[[Device], bool], timeout: float) -> bool:
        """Virtual time: jump from event to event until ``predicate(device)`` holds (it runs in
        the runtime's thread) or ``timeout`` simulated seconds pass; returns whether it held."""
        device = self.device
        return self.runtime.run_until(lambda: bool(predicate(device)), timeout)

    # -- life ------------------------------------------------------------------------------------
    def stop(self) -> None:
        """Close the host ports opened here, the device's port and its runtime thread."""
        self._serial.close()
        if self._owns_runtime:
            self.runtime.stop()


class DeviceFactory:
    """What the ``devsim_device`` fixture yields; usable without pytest as well::

        factory = DeviceFactory()
        try:
            drive = factory("sers", {"address": 1})
            ...
        finally:
            factory.close()
    """

    def __init__(self) -> None:
        self.devices: list[SimDevice] = []
        self._lock = threading.Lock()

    def __call__(
        self,
        kind: str,
        config: Mapping[str, Any] | None = None,
        *,
        transport: str | Mapping[str, Any] = "pty",
        virtual: bool = True,
        name: str | None = None,
        state_dir: str | os.PathLike[str] | None = None,
        boot: bool = True,
    ) -> SimDevice:
        from devsim.scenario.plant import make_transport
        from devsim.scenario.schema import kind_port_defaults
        from devsim.scenario.specs import TransportSpec

        spec = _transport_spec(transport)
        #: a port that declares a network transport (the PCD's Ether-S-Bus on UDP and TCP) keeps
        #: its scheme, on a free port, as in a plant; the others are served on ``transport``
        declared = {port: TransportSpec.parse({scheme: {}}) for port, (scheme, _n) in kind_port_defaults(kind).items()}
        with self._lock:
            taken = {d.name for d in self.devices}
            if name is None:
                name = kind
                number = 2
                while name in taken:
                    name = f"{kind}{number}"
                    number += 1
        runtime = Runtime(virtual=virtual, state_dir=state_dir).start()
        try:
            device = runtime.add_device(kind, name, dict(config or {}))
            transports = {}
            for port_name in device.port_names():
                transports[port_name] = make_transport(declared.get(port_name, spec))
                runtime.serve_sync(device, transports[port_name], port=port_name)
            first = transports[device.port_names()[0]]
            sim = SimDevice(runtime, name, kind, first, spec.kind, transports)
            if boot:
                sim.wait_booted()
        except BaseException:
            runtime.stop()
            raise
        with self._lock:
            self.devices.append(sim)
        return sim

    make = __call__

    def close(self) -> None:
        errors: list[BaseException] = []
        while self.devices:
            device = self.devices.pop()
            try:
                device.stop()
            except Exception as exc:  # noqa: BLE001 - stop the rest, then report
                errors.append(exc)
        if errors:
            raise errors[0]


# -- a plant -----------------------------------------------------------------------------------
def _make_sim_plant_class() -> type:
    from devsim.scenario.plant import Plant

    class SimPlant(Plant):  # type: ignore[misc]
        """A running plant with control helpers (all thread-safe, by device name): the ops of
        :data:`devsim.runtime.ops.CONTROL`, as :class:`SimDevice` runs them."""

        def read(self, device: str, name: str) -> Any:
            return run(self.runtime, rq.Read(device, name))

        def set(self, device: str, name: str, value: Any) -> None:
            run(self.runtime, rq.Set(device, name, value))

        def state(self, device: str) -> dict[str, Any]:
            result: dict[str, Any] = run(self.runtime, rq.State(device))
            return result

        def power_cycle(self, device: str, wipe: bool = False) -> None:
            run(self.runtime, rq.PowerCycle(device, wipe))

        def fault(self, device: str, kind: str, active: bool = True) -> None:
            """Switch a declared fault of ``device`` on or off."""
            run(self.runtime, rq.SwitchFault(device, kind, active))

        def line_fault(self, device: str, kind: str, active: bool = True, *, port: str = "main", **params: Any) -> None:
            """Start or end a fault on the line serving a port of ``device``."""
            run(self.runtime, rq.LineFault(device, kind, active, port, params))

        def now(self) -> float:
            return float(run(self.runtime, rq.Now()))

        def advance(self, seconds: float) -> float:
            return float(run(self.runtime, rq.Advance(seconds)))

        def run_until(self, predicate: Callable[[Plant], bool], timeout: float) -> bool:
            """Virtual time: until ``predicate(plant)`` holds (run in the runtime's thread)."""
            return self.runtime.run_until(lambda: bool(predicate(self)), timeout)

        def device(self, name: str) -> SimDevice:
            """A :class:`SimDevice` view of one device (its port is its own or its bus's);
            stopping the plant stops it."""
            port = self.port_of(name)
            view = SimDevice(self.runtime, name, self.devices[name].kind, self.transports[port], self.kinds[port])
            view._owns_runtime = False
            return view

        def stop(self) -> None:
            self.runtime.stop()

    return SimPlant


def _as_sim_plant(plant: Any) -> Any:
    cls = _sim_plant_class()
    values = {f.name: getattr(plant, f.name) for f in msgspec.structs.fields(plant)}
    return cls(**values)


_SIM_PLANT: list[type] = []


def _sim_plant_class() -> type:
    """``SimPlant``, made on first use so that loading the plugin does not import the scenario
    package (pytest loads the plugin in every session)."""
    if not _SIM_PLANT:
        _SIM_PLANT.append(_make_sim_plant_class())
    return _SIM_PLANT[0]


def __getattr__(name: str) -> Any:
    if name == "SimPlant":
        return _sim_plant_class()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def _plant_spec(source: Any, *bases: Path) -> Any:
    from devsim.core.config import plain
    from devsim.scenario.schema import PlantSpec, load_plant, scenario_from_dict

    if isinstance(source, PlantSpec):
        return source
    if isinstance(source, Mapping):
        data = plain(dict(source))
        if "steps" in data:
            return scenario_from_dict(data)
        return PlantSpec.parse(data)
    return load_plant(_resolve(source, *bases))


class PlantFactory:
    """What the ``devsim_plant`` fixture yields."""

    def __init__(self, *bases: Path) -> None:
        self.bases = bases
        self.plants: list[Any] = []

    def __call__(
        self,
        source: str | os.PathLike[str] | Mapping[str, Any] | Any,
        *,
        virtual: bool = True,
        state_dir: str | os.PathLike[str] | None = None,
        boot: bool = True,
    ) -> Any:
        from devsim.scenario.plant import start_plant

        spec = _plant_spec(source, *self.bases)
        plant = _as_sim_plant(start_plant(spec, virtual=virtual, state_dir=state_dir))
        self.plants.append(plant)
        if boot:
            _wait_booted(plant.runtime, list(plant.devices.values()))
        return plant

    make = __call__

    def close(self) -> None:
        errors: list[BaseException] = []
        while self.plants:
            plant = self.plants.pop()
            try:
                plant.runtime.stop()
            except Exception as exc:  # noqa: BLE001
                errors.append(exc)
        if errors:
            raise errors[0]


# -- scenarios ---------------------------------------------------------------------------------
class ScenarioFailed(Exception):
    """A scenario run as a test failed; ``str()`` is the report."""

    def __init__(self, report: str, result: Any = None) -> None:
        super().__init__(report)
        self.report = report
        self.result = result


def run_scenario_spec(
    source: Any, *bases: Path, mode: str | None = None, default_mode: str = "virtual", **kwargs: Any
) -> Any:
    """Load (a path, relative to ``bases`` first) or build (a dict) a scenario and run it.

    The time mode is ``mode``, else the scenario's own ``time:``, else ``default_mode``: virtual,
    because inside a test session no outside host software drives the plant (``devsim scenario
    run`` defaults to real time for scenarios that do not script the host, so that one can)."""
    from devsim.core.config import plain
    from devsim.scenario.runner import run_scenario
    from devsim.scenario.schema import Scenario, load_scenario, scenario_from_dict

    if isinstance(source, Scenario):
        scenario = source
    elif isinstance(source, Mapping):
        scenario = scenario_from_dict(plain(dict(source)))
    else:
        scenario = load_scenario(_resolve(source, *bases))
    return run_scenario(scenario, mode=mode or scenario.time or default_mode, **kwargs)


def _report(result: Any) -> str:
    from devsim.scenario.report import format_report

    return format_report(result)


# -- pytest hooks and fixtures -------------------------------------------------------------------
def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addini(
        "devsim_collect_scenarios",
        "collect scenario_*.yaml / scenario_*.yml files as devsim scenario tests",
        type="bool",
        default=True,
    )


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers",
        "devsim_scenario(path_or_dict, mode=None, check=True): run a devsim scenario before the test; "
        "fail the test with the scenario report if it fails (result: devsim_scenario_result fixture)",
    )


@pytest.fixture
def devsim_device() -> Iterator[DeviceFactory]:
    """Factory for simulated devices on real ports: ``devsim_device("sers", {...})``."""
    factory = DeviceFactory()
    try:
        yield factory
    finally:
        factory.close()


@pytest.fixture
def devsim_plant(request: pytest.FixtureRequest) -> Iterator[PlantFactory]:
    """Factory for plants from a plant/scenario file (relative to the test file) or a dict."""
    factory = PlantFactory(request.path.parent, request.config.rootpath, Path.cwd())
    try:
        yield factory
    finally:
        factory.close()


_RESULT_KEY = pytest.StashKey[Any]()


@pytest.fixture
def devsim_scenario_result(request: pytest.FixtureRequest) -> Any:
    """The :class:`~devsim.scenario.runner.ScenarioResult` of the test's ``devsim_scenario``
    marker (the scenario runs when this fixture is set up, before the test body)."""
    from devsim.core.config import ConfigError, place
    from devsim.core.typed import Invalid

    marker = request.node.get_closest_marker("devsim_scenario")
    if marker is None:
        raise pytest.UsageError("devsim_scenario_result needs @pytest.mark.devsim_scenario(...) on the test")
    if len(marker.args) != 1:
        raise pytest.UsageError("@pytest.mark.devsim_scenario takes one scenario path or dict")
    options = {k: v for k, v in marker.kwargs.items() if k != "check"}
    try:
        result = run_scenario_spec(marker.args[0], request.path.parent, request.config.rootpath, Path.cwd(), **options)
    except ConfigError as exc:
        pytest.fail("\n".join(exc.messages), pytrace=False)
    except Invalid as exc:  # a scenario given as a dict
        count = len(exc.problems)
        lines = [f"  {place(marker.args[0], loc) or 'scenario'}: {text}" for loc, text in exc.problems]
        pytest.fail(f"devsim_scenario: {count} validation error{'s' if count > 1 else ''} in the scenario\n"
                    + "\n".join(lines), pytrace=False)
    request.node.stash[_RESULT_KEY] = result
    return result


@pytest.fixture(autouse=True)
def _devsim_scenario_marker(request: pytest.FixtureRequest) -> None:
    """Runs the scenario of a ``devsim_scenario`` marker even if the test does not ask for
    ``devsim_scenario_result``."""
    if request.node.get_closest_marker("devsim_scenario") is not None:
        request.getfixturevalue("devsim_scenario_result")


@pytest.hookimpl(tryfirst=True)
def pytest_runtest_call(item: pytest.Item) -> None:
    """A failed marker scenario fails the test (in the call phase, before the test body)."""
    marker = item.get_closest_marker("devsim_scenario")
    if marker is None or not marker.kwargs.get("check", True):
        return
    result = item.stash.get(_RESULT_KEY, None)
    if result is not None and not result.passed:
        pytest.fail(_report(result), pytrace=False)


def pytest_collect_file(file_path: Path, parent: pytest.Collector) -> pytest.Collector | None:
    name = file_path.name
    if not (name.startswith("scenario_") and file_path.suffix in (".yaml", ".yml")):
        return None
    if not parent.config.getini("devsim_collect_scenarios"):
        return None
    return ScenarioFile.from_parent(parent, path=file_path)


class ScenarioFile(pytest.File):
    """A ``scenario_*.yaml`` file: one test item."""

    def collect(self) -> Iterator[ScenarioItem]:
        yield ScenarioItem.from_parent(self, name=self.path.stem)


class ScenarioItem(pytest.Item):
    """Runs one scenario file in its own time mode; fails with the scenario report."""

    def runtest(self) -> None:
        from devsim.core.config import ConfigError

        try:
            result = run_scenario_spec(self.path)
        except ConfigError as exc:
            raise ScenarioFailed("\n".join(exc.messages)) from None
        self.stash[_RESULT_KEY] = result
        self.user_properties.append(("simulated_time", f"{result.sim_time:.6f}"))
        if not result.passed:
            raise ScenarioFailed(_report(result), result)

    def repr_failure(self, excinfo: pytest.ExceptionInfo[BaseException], style: Any = None) -> Any:
        if isinstance(excinfo.value, ScenarioFailed):
            return excinfo.value.report
        return super().repr_failure(excinfo, style=style)

    def reportinfo(self) -> tuple[Path, int | None, str]:
        return self.path, 0, f"devsim scenario {self.path.name}"
