"""A device as a CANopen node (issue 13; canopen's local node over python-can; extra
``devsim-motion[can]``): the object dictionary of :mod:`devsim.facades.canopen_od`, NMT with the
boot-up message, the heartbeat producer (1017h), the SYNC consumer (1005h) and CiA 301's resets (issue 29: reset communication
restores 1000h … 1FFFh, reset node also the 402 objects), and SDO access to every point: an upload reads
the point as the control API does, a download sets it with its validation (a refused value is
aborted with 0609 0030h, value range exceeded; a read-only object 0601 0002h; every abort names the
request's multiplexer: :mod:`devsim.facades.canopen_sdo`).

A kind that declares itself a drive (``Device.drive``) also gets the CiA 402 objects and state
machine (:mod:`devsim.facades.cia402`): controlword 6040h, statusword 6041h, profile position and
profile velocity modes (with 606Dh … 6070h, the velocity window and threshold; 6065h … 6068h,
the following error and position windows, and 60F2h, the positioning option code), homing mode where the
kind has a reference run of its own (607Ch, 6098h, 6099h, 609Ah: :mod:`devsim.facades.cia402_homing`), 6064h/606Ch/60F4h; a fault the model announces (topic ``fault``) sends an
EMCY message.  Hosts in other processes reach the nodes through
:class:`devsim.transports.socketcand.SocketcandServer` (:func:`start_canopen`, ``devsim run
--canopen``).  PDOs: what the master maps into 1600h/1A00h and enables; TPDOs go out on SYNC
(the CAN-ID 1005h names; transmission types 1 … 240; type 0 at the SYNC after a change); with types 254/255 when a mapped value changes (looked at every
inhibit time, else every 10 ms of device time) and when the event timer runs out; RPDOs are
written into their objects, those of types 254/255 as they arrive, synchronous ones (0 … 240) at
the next SYNC (the last one received before it).  ``devsim run --canopen NODE@socketcan:vcan0`` puts the nodes on a
SocketCAN interface instead, where the machine has one.  Callbacks come from the thread that reads
the bus (python-can's notifier; on the socketcand server's virtual bus devsim's
:class:`~devsim.transports.can_reader.BusReader`, which stops without waiting for a frame); ``call``
runs the device access where the device lives (``Runtime.call``)."""

from __future__ import annotations

import asyncio
import io
from collections.abc import Callable
from typing import Any

import can
import canopen
from canopen.sdo.exceptions import SdoAbortedError

from devsim.core.console import warn
from devsim.core.device import Device
from devsim.core.points import BadValue, ReadOnlyName
from devsim.facades import canopen_mapping, library_log
from devsim.facades.canopen_od import SYNC_COB_ID, eds, point_objects
from devsim.facades.canopen_sdo import DevsimSdoServer, check_length
from devsim.facades.cia402 import Cia402

__all__ = ["CHANGE_SAMPLE", "CanopenFacade", "READ_ONLY", "VALUE_RANGE_EXCEEDED", "WRITE_ONLY", "integer32", "load_od",
           "serve_nodes", "start_canopen"]

VALUE_RANGE_EXCEEDED = canopen_mapping.VALUE_RANGE_EXCEEDED  # (0609 0030h)
CHANGE_SAMPLE = 0.010  # s of device time between looks for a change of an event-driven TPDO
READ_ONLY = 0x06010002
WRITE_ONLY = 0x06010001


def load_od(text: str, node_id: int) -> Any:
    """An object dictionary from EDS text (canopen wants a file-like object with a name)."""
    source = io.StringIO(text)
    source.name = "devsim.eds"  # type: ignore[misc]
    return canopen.import_od(source, node_id)


def _direct(fn: Callable[..., Any], *args: Any) -> Any:
    return fn(*args)


class CanopenFacade:
    """``device`` as CANopen node ``node_id``."""

    def __init__(self, device: Device, node_id: int = 1, call: Callable[..., Any] = _direct) -> None:
        if not 1 <= node_id <= 127:
            raise ValueError("a CANopen node id is 1 … 127")
        self.device, self.call = device, call
        self.od = load_od(eds(device.kind, device.description, device.points, drive=device.drive is not None,
                              homing=device.drive is not None and device.drive.homing is not None), node_id)
        self.drive = Cia402(device.drive, device.model, device.clock) if device.drive is not None else None
        self._unlisten = device.model.listen("fault", self._emergency)
        self._unlisten_power = device.model.listen("power_on", self._power_on)
        self._pdos_on = False
        self._syncs = 0
        self._sync_id: int | None = None  # the CAN-ID of the SYNC consumed (1005h)
        self._timers: dict[tuple[int, str], Any] = {}  # event-driven TPDOs: device-clock timers
        self._sent: dict[int, bytes] = {}  # event-driven TPDOs: the data they last carried
        self._actuate: dict[int, list[tuple[int, int, bytes]]] = {}  # synchronous RPDOs: for the next SYNC
        self.lost = 0  # TPDOs and EMCY messages the bus refused (see _send)
        self._refused = False  # the last message was refused
        self.node = canopen.LocalNode(node_id, self.od)
        self.node.sdo = self.sdo = DevsimSdoServer(0x600 + node_id, 0x580 + node_id, self.node)
        self.objects = {index: point for index, point in point_objects(device.points)}
        self.node.add_read_callback(self._read)
        self.node.add_write_callback(self._write)

    def attach(self, network: canopen.Network) -> None:
        """Join ``network`` and boot: the boot-up message, then pre-operational (the heartbeat
        starts if 1017h is set); the NMT resets boot again (:meth:`_reset_communication`,
        :meth:`_reset_node`).  Entering OPERATIONAL the node takes the PDO configuration the
        master wrote: TPDOs with a transmission type 1 … 240 go out after every that many SYNCs,
        those with 254/255 on a change of their values and every event-timer period (device
        time), RPDOs are written into their objects as they arrive."""
        network.add_node(self.node)
        network.unsubscribe(0, self.node.nmt.on_command)  # the NMT commands come to _nmt alone
        network.subscribe(0, self._nmt)
        self._consume_sync(SYNC_COB_ID)
        self._boot()

    def _consume_sync(self, can_id: int) -> None:
        """The SYNC consumer listens to ``can_id`` (1005h, CiA 301 §7.5.2.5), no longer to the one before."""
        network = self.node.network
        if self._sync_id is not None:
            network.unsubscribe(self._sync_id, self._sync)
        self._sync_id = can_id
        network.subscribe(can_id, self._sync)

    # -- NMT (CiA 301: the NMT state machine) ---------------------------------------------------------
    def _nmt(self, can_id: int, data: bytes, timestamp: float) -> None:
        if len(data) < 2 or data[1] not in (0, self.node.id):
            return
        reset = RESETS.get(data[0])
        if reset is not None:
            reset(self)
            return
        self.node.nmt.on_command(can_id, data, timestamp)
        if self.node.nmt.state == "OPERATIONAL" and not self._pdos_on:
            self._start_pdos()
        elif self.node.nmt.state != "OPERATIONAL":
            self._stop_pdos()

    def _boot(self) -> None:
        """Initialisation ends: one boot-up message, then PRE-OPERATIONAL (with the heartbeat
        1017h asks for)."""
        self.node.nmt.send_command(0x81)  # INITIALISING: canopen sends the boot-up message
        self.node.nmt.send_command(0x80)  # PRE-OPERATIONAL, the heartbeat from 1017h

    def _reset_communication(self) -> None:
        """NMT reset communication: the communication objects (1000h … 1FFFh: 1017h, the PDO
        parameters) back to their power-on values, PDOs and heartbeat stopped, then the boot."""
        self._stop_pdos()
        self.sdo.reset()
        self.node.nmt.stop_heartbeat()
        self._forget(0x1000, 0x1FFF)
        self._consume_sync(SYNC_COB_ID)
        self._boot()

    def _reset_node(self) -> None:
        """NMT reset node (reset application, then reset communication): also the application
        objects (2000h … 9FFFh) back to their power-on values: the 402 objects, the drive
        disabled and in Switch on disabled.  The objects from 2000h on that are the device's
        points show the simulated device, which the node's reset does not switch off."""
        self._stop_pdos()
        if self.drive is not None:
            self.call(self.drive.reset)
        self._forget(0x2000, 0x9FFF)
        self._reset_communication()

    def _power_on(self) -> None:
        """The device powers up (a power cycle, its supply back on), and the node with it: it
        starts as after an NMT reset node, with its power-on values, Switch on disabled and a
        boot-up message (a drive in Fault before is not in Fault now unless its device still is)."""
        if self.node.has_network():
            self._reset_node()

    def _forget(self, first: int, last: int) -> None:
        """Drop what masters wrote into objects ``first`` … ``last``: they read their EDS default."""
        for index in [index for index in self.node.data_store if first <= index <= last]:
            del self.node.data_store[index]

    # -- PDOs ---------------------------------------------------------------------------------
    def _start_pdos(self) -> None:
        self._pdos_on = True
        self._syncs = 0
        self.node.tpdo.read(from_od=False)  # what the master configured (SDO into the data store)
        self.node.rpdo.read(from_od=False)  # (subscribes the enabled RPDOs)
        for rpdo in self.node.rpdo.map.values():
            if rpdo.enabled:
                rpdo.add_callback(self._received)
        for tpdo in self.node.tpdo.map.values():
            if tpdo.enabled and (tpdo.trans_type or 0) >= 254:
                self.call(self._start_event_driven, tpdo)
            elif tpdo.enabled and tpdo.trans_type == 0:  # synchronous acyclic: the values as of now
                self._sent[id(tpdo)] = self._data(tpdo)

    def _stop_pdos(self) -> None:
        """Leaving OPERATIONAL: no TPDO goes out, no RPDO is taken."""
        self._pdos_on = False
        self._actuate.clear()
        self.call(self._cancel_timers)
        for rpdo in self.node.rpdo.map.values():
            rpdo.callbacks.clear()
            if rpdo.cob_id is not None and rpdo.on_message in self.node.network.subscribers.get(rpdo.cob_id, []):
                self.node.network.unsubscribe(rpdo.cob_id, rpdo.on_message)

    def _start_event_driven(self, tpdo: Any) -> None:
        """An event-driven TPDO (types 254/255, CiA 301 §7.5.2.35): sent when a mapped value
        changes (looked at every inhibit time, or every ``CHANGE_SAMPLE`` s without one, in
        device time) and, with an event timer, when that long passed without a transmission."""
        self._sent[id(tpdo)] = self._data(tpdo)
        self._arm(tpdo, "event")
        self._arm(tpdo, "change")

    def _arm(self, tpdo: Any, why: str) -> None:
        key = (id(tpdo), why)
        old = self._timers.pop(key, None)
        if old is not None:
            old.cancel()
        if why == "event":
            if not tpdo.event_timer:
                return
            delay = tpdo.event_timer / 1000
        else:
            delay = tpdo.inhibit_time / 10_000 if tpdo.inhibit_time else CHANGE_SAMPLE

        def tick() -> None:
            self._timers.pop(key, None)
            if not self._pdos_on:
                return
            if why == "event" or self._data(tpdo) != self._sent.get(id(tpdo)):
                self._transmit(tpdo)  # re-arms the event timer
            if why == "change":
                self._arm(tpdo, "change")

        self._timers[key] = self.device.clock.call_later(delay, tick)

    def _cancel_timers(self) -> None:
        for timer in self._timers.values():
            timer.cancel()
        self._timers.clear()

    def _data(self, tpdo: Any) -> bytes:
        return b"".join(self.node.get_data(v.index, v.subindex) for v in tpdo.map if v.length)

    def _transmit(self, tpdo: Any) -> None:
        carried = []
        for variable in tpdo.map:
            if variable.length:
                data = self.node.get_data(variable.index, variable.subindex)
                variable.set_data(data)
                carried.append(data)
        self._send(tpdo.transmit)
        if (tpdo.trans_type or 0) >= 254:
            self._sent[id(tpdo)] = b"".join(carried)
            self._arm(tpdo, "event")
        elif tpdo.trans_type == 0:
            self._sent[id(tpdo)] = b"".join(carried)

    def _sync(self, can_id: int, data: bytes, timestamp: float) -> None:
        """A SYNC: the synchronous TPDOs due go out (with the values as of the SYNC), then the
        synchronous RPDOs received since the last one are taken."""
        if not self._pdos_on:
            return
        self._syncs += 1
        for tpdo in self.node.tpdo.map.values():
            if not tpdo.enabled or (tpdo.trans_type or 0) > 240:
                continue
            if tpdo.trans_type == 0:  # synchronous acyclic (CiA 301): at the SYNC after a change
                if self._data(tpdo) != self._sent.get(id(tpdo)):
                    self._transmit(tpdo)
            elif self._syncs % tpdo.trans_type == 0:
                self._transmit(tpdo)
        actuate = list(self._actuate.values())
        self._actuate.clear()
        for values in actuate:
            self._take(values)

    def _received(self, rpdo: Any) -> None:
        """An RPDO's values: into their objects at once (types 254/255), or at the next SYNC
        (synchronous types 0 … 240, CiA 301 §7.5.2.35: the data a synchronous RPDO carries is
        actuated at the SYNC that follows it; a later one before that SYNC replaces it)."""
        values = [(v.index, v.subindex, v.get_data()) for v in rpdo.map if v.length]
        if rpdo.trans_type is not None and rpdo.trans_type <= 240:
            self._actuate[rpdo.cob_id] = values
            return
        self._take(values)

    def _take(self, values: list[tuple[int, int, bytes]]) -> None:
        """Values into their objects; one the object refuses (an unsupported mode of operation, a
        value out of range) is dropped: a PDO has no answer to carry a refusal."""
        for index, subindex, data in values:
            try:
                self.node.set_data(index, subindex, data, check_writable=True)
            except SdoAbortedError:
                continue

    def _emergency(self, axis: int = 1, code: int = 0x1000) -> None:
        """A fault the model announces: an EMCY message (error register bit 0, generic error);
        none while the node is STOPPED (CiA 301 §7.3.2.2: EMCY is served in PRE-OPERATIONAL and
        OPERATIONAL)."""
        if axis == 1 and self.drive is not None:
            self.drive.error_code = code  # (603Fh shows it)
        if axis == 1 and self.node.has_network() and self.node.nmt.state != "STOPPED":
            self._send(self.node.emcy.send, code, 0x01)

    def _error_reset(self) -> None:
        """The fault reset cleared the drive's fault: EMCY 0000h, "error reset or no error", with
        the error register as it is now (CiA 301 §7.2.7, the EMCY producer back in error free)."""
        if self.node.has_network() and self.node.nmt.state != "STOPPED":
            self._send(self.node.emcy.send, 0x0000, 0x00)

    def _send(self, send: Callable[..., Any], *args: Any) -> None:
        """A message of the node's own onto the bus.  One the bus refuses (python-can's
        ``CanError``: a SocketCAN interface down, bus-off, a full transmit queue) is lost, as on a
        node whose controller cannot transmit, and counted in :attr:`lost`: the device, the
        fault it announces and the PDO timers go on, and the next message is tried again.  One
        line on stderr when the bus starts refusing, one when it takes a message again."""
        try:
            send(*args)
        except can.CanError as exc:
            if not self._refused:
                warn(f"devsim: {self.device.name}.canopen: the bus refused a message ({exc}); "
                     "messages are lost until it takes them again")
                self._refused = True
            self.lost += 1
            return
        if self._refused:
            self._refused = False
            warn(f"devsim: {self.device.name}.canopen: the bus takes messages again ({self.lost} lost so far)")

    def close(self) -> None:
        self._unlisten()
        self._unlisten_power()
        self.call(self._cancel_timers)
        if self.drive is not None:
            self.call(self.drive.cancel)

    def _read(self, index: int, subindex: int, od: Any) -> Any:
        if self.drive is not None and (index, subindex) in HOMING_SPEEDS:
            return self.call(lambda d: d.homing.speeds[subindex - 1], self.drive)
        if self.drive is not None and index in DRIVE_READS:
            return self.call(DRIVE_READS[index], self.drive)
        point = self.objects.get(index)
        if point is None:
            return None
        if not point.readable:
            raise SdoAbortedError(WRITE_ONLY)
        value = self.call(self.device.read, point.name)
        if value is None:
            return 0
        return bool(value) if point.type == "bool" else value

    def _write(self, index: int, subindex: int, od: Any, data: bytes) -> None:
        check_length(od, data)  # (before anything decodes it: an SDO download's or an RPDO's bytes)
        if canopen_mapping.is_pdo_parameter(index):
            canopen_mapping.check(self.node, index, subindex, data)  # (CiA 301: what a PDO takes)
            return
        if index == 0x1005:
            self._consume_sync(canopen_mapping.sync_cob_id(data))
            return
        if self.drive is not None and (index in DRIVE_WRITES or (index, subindex) in HOMING_SPEEDS):
            write = DRIVE_WRITES.get(index) or (lambda d, v: d.homing.write_speed(subindex, int(v)))
            faulted = index == 0x6040 and self.call(self.drive.in_fault)
            try:
                self.call(write, self.drive, od.decode_raw(data))
            except (BadValue, ReadOnlyName, ValueError):
                raise SdoAbortedError(VALUE_RANGE_EXCEEDED) from None
            if faulted and not self.call(self.drive.in_fault):
                self._error_reset()
            return
        point = self.objects.get(index)
        if point is None:
            return
        if not point.settable:
            raise SdoAbortedError(READ_ONLY)
        value = od.decode_raw(data)
        if point.type == "bool" and data[:1] not in (b"\x00", b"\x01"):
            raise SdoAbortedError(VALUE_RANGE_EXCEEDED)  # (CiA 301's BOOLEAN: 0 false, 1 true)
        try:
            self.call(self.device.set, point.name, bool(value) if point.type == "bool" else value)
        except (BadValue, ReadOnlyName, ValueError):
            raise SdoAbortedError(VALUE_RANGE_EXCEEDED) from None


async def start_canopen(runtime: Any, devices: list[Device], spec: str) -> list[str]:
    """Serve ``devices`` as CANopen nodes ``NODE``, ``NODE+1`` … (``devsim run --canopen``):
    ``spec`` is ``NODE``, ``NODE@[HOST:]PORT`` or ``NODE@socketcan:CHANNEL`` (see
    :func:`serve_nodes`).  Returns one line per device for ``devsim run`` to print."""
    node_text, _, where = spec.partition("@")
    first = int(node_text)
    if not 1 <= first <= 128 - len(devices):
        raise ValueError(f"--canopen: node ids {first} … {first + len(devices) - 1} are not all in 1 … 127")
    return await serve_nodes(runtime, [(device, first + offset) for offset, device in enumerate(devices)], where)


async def serve_nodes(runtime: Any, nodes: list[tuple[Device, int]], where: str = "") -> list[str]:
    """Put each (device, node id) on one CAN network that hosts in other processes reach:
    ``where`` is ``[HOST:]PORT`` (a python-can virtual bus behind a socketcand server, default
    127.0.0.1:29536, loopback unless a host is named) or ``socketcan:CHANNEL`` (a SocketCAN
    interface such as ``vcan0``, where the machine has one).  Returns one line per node."""
    import os

    library_log.limit("canopen", "canopen")  # (a traceback for every short SDO request)
    library_log.limit("can", "can")
    ids = [node_id for _, node_id in nodes]
    if len(set(ids)) != len(ids):
        raise ValueError(f"CANopen node ids on one network must differ: {sorted(ids)}")
    if where.startswith("socketcan:"):
        channel = where.removeprefix("socketcan:")
        network = canopen.Network()
        try:
            network.connect(interface="socketcan", channel=channel)
        except (OSError, can.CanError, ValueError, ImportError) as exc:
            raise ValueError(f"--canopen: SocketCAN {channel!r} cannot be opened here: {exc}") from None
        _attach_all(runtime, nodes, network)

        async def close_socketcan() -> None:
            await asyncio.to_thread(network.disconnect)  # (as close() below)

        runtime.add_closer(close_socketcan)
        return [f"{device.name}.canopen: socketcan {channel} node {node_id}" for device, node_id in nodes]

    from can.interfaces.virtual import VirtualBus

    from devsim.transports.can_reader import BusReader
    from devsim.transports.socketcand import SocketcandServer

    host, _, port_text = where.rpartition(":")
    network = canopen.Network()
    channel = f"devsim-{os.getpid()}-{id(runtime)}-{id(network)}"
    network.bus = bus = VirtualBus(channel=channel)
    network.notifier = BusReader(bus, network.listeners)  # type: ignore[assignment]  # (for connect()'s
    # can.Notifier, whose stop waits up to NOTIFIER_CYCLE, 1 s, for a frame: see can_reader)
    _attach_all(runtime, nodes, network)
    server = SocketcandServer(channel, host or "127.0.0.1", int(port_text or 29536))
    try:
        await server.start()
    except BaseException:
        network.disconnect()
        raise

    async def close() -> None:
        await server.close()
        # (in a thread: the reader may be delivering a frame whose device access waits for the loop)
        await asyncio.to_thread(network.disconnect)

    runtime.add_closer(close)
    return [f"{device.name}.canopen: socketcand {server.address} can0 node {node_id}" for device, node_id in nodes]


def _attach_all(runtime: Any, nodes: list[tuple[Device, int]], network: canopen.Network) -> None:
    for device, node_id in nodes:
        CanopenFacade(device, node_id, call=runtime.call).attach(network)


def integer32(value: float) -> int:
    """An actual value (6064h, 606Ch, 60F4h: INTEGER32) as its object shows it: rounded, and past
    the type's range rolled over, as a drive's 32-bit position counter rolls over.  [SIM-CHOICE]
    CiA 402 gives these objects 32 bits and says nothing of a value beyond them; the drive's own
    position is not bounded so (a home offset of -2^31 puts 6064h at 2^31 at the home position)."""
    return (round(value) + 0x8000_0000) % 0x1_0000_0000 - 0x8000_0000


RESETS: dict[int, Callable[[CanopenFacade], None]] = {
    0x81: CanopenFacade._reset_node,
    0x82: CanopenFacade._reset_communication,
}
"""The NMT reset commands (CiA 301): reset node, reset communication."""

DRIVE_READS: dict[int, Callable[[Cia402], int]] = {
    0x1001: lambda d: d.error_register,
    0x603F: lambda d: d.error_code_object,
    0x6040: lambda d: d.controlword,
    0x6041: lambda d: d.statusword,
    0x6060: lambda d: d.mode,
    0x6061: lambda d: d.mode,
    0x6064: lambda d: integer32(d.actions.position(d.model)),
    0x6065: lambda d: d.position_watch.following_window,
    0x6066: lambda d: d.position_watch.following_time,
    0x6067: lambda d: d.position_watch.window,
    0x6068: lambda d: d.position_watch.window_time,
    0x606C: lambda d: integer32(d.actions.velocity(d.model)),
    0x606D: lambda d: d.watch.window,
    0x606E: lambda d: d.watch.window_time,
    0x606F: lambda d: d.watch.threshold,
    0x6070: lambda d: d.watch.threshold_time,
    0x607A: lambda d: d.target_position,
    0x6081: lambda d: d.profile_velocity,
    0x60F2: lambda d: d.setpoints.option,
    0x60F4: lambda d: integer32(d.actions.following_error(d.model)),
    0x60FF: lambda d: d.target_velocity,
    0x6502: lambda d: d.supported_modes,
    0x607C: lambda d: d.homing.offset,
    0x6098: lambda d: d.homing.method,
    0x609A: lambda d: d.homing.acceleration,
}
"""The CiA 402 objects as the drive state shows them, and the error register 1001h (CiA 301: bit 0
while the drive has a fault, as its EMCY says)."""

DRIVE_WRITES: dict[int, Callable[[Cia402, Any], None]] = {
    0x6040: Cia402.write_controlword,
    0x6060: lambda d, v: d.write_mode(int(v)),
    0x607A: lambda d, v: setattr(d, "target_position", int(v)),
    0x6081: lambda d, v: setattr(d, "profile_velocity", int(v)),
    0x606D: lambda d, v: d.watch.set("window", v),
    0x606E: lambda d, v: d.watch.set("window_time", v),
    0x606F: lambda d, v: d.watch.set("threshold", v),
    0x6070: lambda d, v: d.watch.set("threshold_time", v),
    0x6065: lambda d, v: d.position_watch.set("following_window", v),
    0x6066: lambda d, v: d.position_watch.set("following_time", v),
    0x6067: lambda d, v: d.position_watch.set("window", v),
    0x6068: lambda d, v: d.position_watch.set("window_time", v),
    0x60F2: lambda d, v: d.setpoints.write_option(int(v)),
    0x60FF: Cia402.write_target_velocity,
    0x607C: lambda d, v: setattr(d.homing, "offset", int(v)),
    0x6098: lambda d, v: d.homing.write_method(int(v)),
    0x609A: lambda d, v: d.homing.write_acceleration(int(v)),
}
HOMING_SPEEDS = frozenset(((0x6099, 1), (0x6099, 2)))
"""6099h's subs (homing speeds: during search for switch, for zero), read and written as such."""
"""Writing the CiA 402 objects."""
