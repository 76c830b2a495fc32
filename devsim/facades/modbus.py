"""A device's declared points served over Modbus with pymodbus 3.x (issue 13): Modbus TCP through
pymodbus's own server, Modbus RTU through pymodbus's RTU framer on any devsim serial transport (a
pty, raw TCP, RFC 2217).  Both use pymodbus's current device model (``SimDevice`` with an
``action``): every read takes the device's present values, every write goes through the device's
``set`` with its validation; a value the device refuses is exception 03 (illegal data value), an
address outside the map 02 (illegal data address).  Extra ``devsim-motion[modbus]``.

The map is :class:`devsim.facades.modbus_map.ModbusMap`; everything here runs in the runtime's
event loop, beside the device's own ports.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable, Sequence
from typing import Any

from pymodbus.constants import ExcCodes
from pymodbus.framer import FramerRTU
from pymodbus.pdu import DecodePDU, ExceptionResponse
from pymodbus.server import ModbusTcpServer
from pymodbus.simulator import DataType, SimData, SimDevice
from pymodbus.simulator.simcore import SimCore

from devsim.core.device import Device, SerialSettings
from devsim.core.points import BadValue, ReadOnlyName
from devsim.facades import library_log
from devsim.facades.modbus_map import BITS, ModbusMap, from_words, to_words

__all__ = ["ModbusFacade", "ModbusRtuEndpoint", "device_map", "line_settings", "serve_tcp", "start_modbus"]

TABLE_OF = {1: "coil", 5: "coil", 15: "coil", 2: "discrete", 3: "holding", 6: "holding", 16: "holding",
            23: "holding", 4: "input"}


class ModbusFacade:
    """One device behind its Modbus map, as a pymodbus ``SimDevice`` with unit id ``unit``."""

    def __init__(self, device: Device, mapping: ModbusMap | None = None, unit: int = 1) -> None:
        self.device = device
        self.map = mapping if mapping is not None else ModbusMap.generate(device.points)
        self.unit = unit

    def sim_device(self) -> SimDevice:
        blocks: dict[str, list[SimData]] = {table: [] for table in ("coil", "discrete", "holding", "input")}
        for table in BITS:
            size = max(self.map.size(table), 1)
            blocks[table].append(SimData(0, count=size, values=False, datatype=DataType.BITS))
        for entry in self.map.entries:
            if entry.table not in BITS:
                blocks[entry.table].append(SimData(entry.address, count=2, values=0, datatype=DataType.REGISTERS))
        for table in ("holding", "input"):
            if not blocks[table]:
                blocks[table].append(SimData(0, count=1, datatype=DataType.INVALID))
        return SimDevice(self.unit, simdata=(blocks["coil"], blocks["discrete"], blocks["holding"], blocks["input"]),
                         use_bit_addressing=True, action=self._action)

    # -- pymodbus calls this before it reads or writes its registers ----------------------------
    async def _action(self, function: int, start: int, address: int, count: int, registers: list[int],
                      values: Sequence[int] | Sequence[bool] | None) -> ExcCodes | None:
        table = TABLE_OF.get(function)
        if table is None:
            return ExcCodes.ILLEGAL_FUNCTION
        try:
            if table in BITS:
                return self._bits(table, address, count, registers, values)
            return self._words(table, start, address, count, registers, values)
        except (BadValue, ReadOnlyName, ValueError):
            return ExcCodes.ILLEGAL_VALUE
        except Exception:  # noqa: BLE001 - a device error is the device's failure, not the server's
            return ExcCodes.DEVICE_FAILURE

    def _bits(self, table: str, address: int, count: int, registers: list[int],
              values: Sequence[int] | Sequence[bool] | None) -> ExcCodes | None:
        if values is not None:
            targets = [self.map.find(table, address + i) for i in range(len(values))]
            if any(t is None for t in targets):
                return ExcCodes.ILLEGAL_ADDRESS
            checked = [(t[0].name, self.device.check(t[0].name, bool(v))) for t, v in zip(targets, values, strict=True)
                       if t is not None]
            for name, value in checked:
                self.device.set(name, value)
            return None
        first = address // 16
        for register in range(first, min(first + count, len(registers))):
            word = 0
            for bit in range(16):
                found = self.map.find(table, register * 16 + bit)
                if found is not None and self._value(found[0].name):
                    word |= 1 << bit
            registers[register] = word
        return None

    def _words(self, table: str, start: int, address: int, count: int, registers: list[int],
               values: Sequence[int] | Sequence[bool] | None) -> ExcCodes | None:
        touched = {}
        for offset in range(len(values) if values is not None else count):
            found = self.map.find(table, address + offset)
            if found is None:
                return ExcCodes.ILLEGAL_ADDRESS
            touched[found[0].name] = found[0]
        if values is None:
            for entry in touched.values():
                high, low = to_words(self._value(entry.name), entry.scale)
                index = entry.address - start
                registers[index : index + 2] = [high, low]
            return None
        changes = []
        for entry in touched.values():
            words = list(to_words(self._value(entry.name), entry.scale))
            for i in range(2):
                written = entry.address + i - address
                if 0 <= written < len(values):
                    words[i] = int(values[written])
            value = from_words(words[0], words[1], entry.scale, entry.type)
            changes.append((entry.name, self.device.check(entry.name, value)))
        for name, value in changes:
            self.device.set(name, value)
        return None

    def _value(self, name: str) -> Any:
        point = self.device.points.find(name)
        if point is None or point.get is None:
            return 0  # a write-only point reads 0
        value = self.device.read(name)
        return 0 if value is None else value


async def serve_tcp(facade: ModbusFacade, host: str = "127.0.0.1", port: int = 502) -> tuple[ModbusTcpServer, int]:
    """Modbus TCP on ``host:port`` (loopback unless the user names a host); returns the server
    and the port it listens on (``port`` 0: one the system chose)."""
    library_log.limit("pymodbus", "modbus")
    server = ModbusTcpServer(facade.sim_device(), address=(host, port))
    await server.serve_forever(background=True)
    sockets = getattr(server.transport, "sockets", None) or []
    bound = sockets[0].getsockname()[1] if sockets else port
    return server, int(bound)


class ModbusRtuEndpoint:
    """Modbus RTU as the target of a devsim line (a pty, raw TCP, RFC 2217): pymodbus's RTU framer
    finds the frames, the device's ``SimDevice`` answers; other unit ids get silence, unit 0 (a
    broadcast) is carried out without an answer."""

    def __init__(self, facade: ModbusFacade, settings: SerialSettings | None = None) -> None:
        library_log.limit("pymodbus", "modbus")
        self.facade = facade
        self.core = SimCore(facade.sim_device())
        self.framer = FramerRTU(DecodePDU(is_server=True))
        self._buffer = b""
        self._write: Callable[[bytes], None] | None = None
        self._settings = settings or SerialSettings(19200, 8, "E", 1)

    @property
    def serial_settings(self) -> SerialSettings:
        return self._settings

    def attach(self, write: Callable[[bytes], None] | None) -> None:
        self._write = write

    def host_disconnected(self) -> None:
        self._buffer = b""

    def feed(self, data: bytes) -> None:
        self._buffer += data
        while len(self._buffer) >= 4:
            size = self._frame_size(self._buffer)
            if size is None:
                self._buffer = self._buffer[1:]  # not the start of a frame: resynchronise
                continue
            if size == 0 or len(self._buffer) < size:
                break  # wait for the rest
            try:
                _, pdu = self.framer.handleFrame(self._buffer[:size], 0, 0)
            except Exception:  # noqa: BLE001 - a frame pymodbus cannot decode
                pdu = None
            if pdu is None:  # a bad CRC: garbage, or a frame start we misread
                self._buffer = self._buffer[1:]
                continue
            self._buffer = self._buffer[size:]
            if pdu.dev_id in (self.facade.unit, 0):
                asyncio.get_running_loop().create_task(self._answer(pdu))
        if len(self._buffer) > 512:
            self._buffer = self._buffer[-256:]

    def _frame_size(self, data: bytes) -> int | None:
        """How long the frame starting at ``data`` is (0: not known yet), or None if no request
        starts here.  pymodbus's own RTU decoder takes everything after a frame, as a line's
        silence would; frames back to back on a pty must be cut here."""
        pdu_class = self.framer.decoder.lookupPduClass(data)
        if pdu_class is None:
            return None
        return int(pdu_class.calculateRtuFrameSize(data) or 0)

    async def _answer(self, pdu: Any) -> None:
        try:
            response = await pdu.datastore_update(self.core, self.facade.unit)
        except Exception:  # noqa: BLE001
            response = ExceptionResponse(pdu.function_code, ExcCodes.DEVICE_FAILURE)
        if pdu.dev_id == 0 or response is None or self._write is None:
            return
        response.dev_id, response.transaction_id = pdu.dev_id, pdu.transaction_id
        self._write(self.framer.buildFrame(response))


def line_settings(text: str) -> SerialSettings:
    """``"19200 8E1"`` as line settings (baud rate, data bits, parity N/E/O, stop bits)."""
    try:
        baud, frame = text.split()
        return SerialSettings(int(baud), int(frame[0]), frame[1].upper(), float(frame[2:]))
    except (ValueError, IndexError):
        raise ValueError(f"line settings are like '19200 8E1', not {text!r}") from None


def device_map(device: Device, layout: str = "points", overrides: dict[str, Any] | None = None) -> ModbusMap:
    """The map a device is served with: generated from its points (``points``), or the kind's own
    mirror of its families (``mirror``, e.g. the PCD's registers and flags, spec pcd4h3 §9.8)."""
    if layout == "mirror":
        if overrides:
            raise ValueError("the mirror layout takes no map overrides")
        return ModbusMap.mirror(device.points)
    if layout != "points":
        raise ValueError(f"a Modbus layout is points or mirror, not {layout!r}")
    return ModbusMap.generate(device.points, overrides)


async def start_modbus(runtime: Any, device: Device, spec: str, *, unit: int = 1,
                       overrides: dict[str, Any] | None = None, trace: str | None = None,
                       line: str = "19200 8E1", layout: str = "points") -> tuple[str, Any]:
    """Serve ``device`` over Modbus in ``runtime`` (in its loop) as ``spec`` says: ``tcp:[HOST:]PORT``
    (Modbus TCP, loopback unless a host is named; pymodbus's own server, not traced), ``rtu`` (RTU
    on a new pty) or ``rtu:LINK`` (a pty with a stable symlink) at the ``line`` settings (Modbus's
    default 19200 8E1).  The port key is ``NAME.modbus``; returns what a host opens and the pty
    transport (None for TCP)."""
    facade = ModbusFacade(device, device_map(device, layout, overrides), unit)
    key = f"{device.name}.modbus"
    scheme, _, rest = spec.partition(":")
    if scheme == "tcp":
        host, _, number = rest.rpartition(":")
        server, bound = await serve_tcp(facade, host or "127.0.0.1", int(number or 502))
        runtime.add_closer(server.shutdown)
        address = f"{host or '127.0.0.1'}:{bound}"
        runtime.ports[key] = address
        return address, None
    if scheme != "rtu":
        raise ValueError(f"--modbus: expected tcp:[HOST:]PORT, rtu or rtu:LINK, not {spec!r}")
    from devsim.transports.pty import PtyTransport

    transport = PtyTransport(link=rest or None)
    await runtime.serve_target([key], ModbusRtuEndpoint(facade, line_settings(line)), transport, trace=trace)
    return str(getattr(transport, "url", "") or transport.address), transport
