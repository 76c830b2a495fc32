"""A plant's devices served by one OPC UA server, through asyncua (issue 14; extra
``devsim-motion[opcua]``).

One server per plant, endpoint ``opc.tcp://127.0.0.1:4840/devsim/`` by default (loopback unless
the user names a host), namespace ``urn:devsim``.  The address space is the one
:mod:`devsim.facades.opcua_space` describes: under ``Objects`` an object per device with a
variable per declared point, the properties ``Kind`` and ``FaultKinds``, and the methods
``Fault(kind: String, active: Boolean)`` and ``PowerCycle(wipe: Boolean)``.

* **Reads** of a point variable read the device at that moment (``Device.read``).
* **Writes** go through ``Device.set`` with its validation: a value of another type than the
  variable's DataType (a Double variable takes only Double, an Int32 only Int32 ...) is
  ``Bad_TypeMismatch``, one the point refuses ``Bad_OutOfRange``, a read-only point
  ``Bad_NotWritable``; nothing changes then.  asyncua's attribute and method services are
  replaced by :class:`devsim.facades.opcua_services.PointAttributes` (the point variables, and
  Part 4's status codes for what may not be written) and ``DeviceMethods`` (Part 4's checks of a
  call's object and arguments).
* **Requests that do not decode** (an enumeration's value out of its range: a timestampsToReturn
  of 5) are answered with Part 4's status (``Bad_TimestampsToReturnInvalid``,
  ``Bad_MonitoringModeInvalid``, ``Bad_DecodingError``), not asyncua's ``Bad_InternalError``:
  :class:`devsim.facades.opcua_decoding.FacadeServer`.
* **Subscriptions**: a :class:`devsim.core.watch.PointWatch` per device samples the points every
  ``period`` seconds of device time (virtual time in tests) and writes what changed into the
  address space, so data-change monitored items see it; a write from a client is sampled at once
  (and reported at once to an item whose last value is older than the item's sampling interval:
  :class:`devsim.facades.opcua_monitoring.Spacing`).
  The period is each point variable's MinimumSamplingInterval (in ms; Part 3, 5.6.2: "how fast the
  Server can reasonably sample the value for changes"), and no Value item of a point is revised to
  a shorter samplingInterval (Part 4, 5.12.1.2).
  Each monitored item is checked as Part 4 5.12.2.4 asks before asyncua creates it (its node,
  attribute, IndexRange, dataEncoding and filter; :mod:`devsim.facades.opcua_monitoring`).
* **Events** (``DeviceFaultEventType``, with ``FaultKind``, ``Active``, ``Axis``, ``Code``):
  when a declared fault is switched on or off (the ``Fault`` method, the control API, a
  scenario: the model's ``fault_switched`` topic) and when the model announces ``fault(axis,
  code)`` (as EMCY does on CANopen).  Each event is emitted by the device object and by the
  ``Server`` object (SourceNode the device), so a client may subscribe to either.

Everything runs as tasks in the runtime's event loop, beside the devices (``start_opcua``).
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Callable, Sequence
from datetime import UTC, datetime
from pathlib import Path
from typing import Any
from urllib.parse import quote, urlparse

from asyncua import ua
from asyncua.server.event_generator import EventGenerator

import devsim
from devsim.core.device import Device
from devsim.core.points import BadValue, ReadOnlyName, UnknownName
from devsim.core.watch import PointWatch
from devsim.facades import library_log
from devsim.facades.opcua_decoding import FacadeServer
from devsim.facades.opcua_services import DeviceMethods, NodeView, PointAttributes, call_result
from devsim.facades.opcua_space import (
    DEFAULT_ENDPOINT,
    NAMESPACE,
    TypeMismatch,
    Variable,
    endpoint_url,
    eu_information,
    from_opcua,
    to_opcua,
    variables,
)
from devsim.runtime import Runtime
from devsim.runtime import requests as rq
from devsim.runtime.ops import run

__all__ = ["DEFAULT_ENDPOINT", "OpcuaFacade", "endpoint_url", "start_opcua"]

_BAD = ua.StatusCodes
_READ, _WRITE = ua.AccessLevel.CurrentRead.mask, ua.AccessLevel.CurrentWrite.mask
_NOT_READABLE = ua.DataValue(StatusCode=ua.StatusCode(_BAD.BadNotReadable))


class _Bound:
    """One point variable of one device, as the server's node."""

    __slots__ = ("device", "node_id", "stamped", "variable", "vtype")

    def __init__(self, device: _DeviceNode, variable: Variable, node_id: ua.NodeId) -> None:
        self.device, self.variable, self.node_id = device, variable, node_id
        self.vtype = ua.VariantType[variable.data_type]
        #: A write's timestamps (Part 4, 5.10.4.2 Table 59: "the Server shall use these values"):
        #: (the device's value right after it, the written DataValue), until that value changes.
        self.stamped: tuple[Any, ua.DataValue] | None = None

    def read(self) -> ua.DataValue:
        return self.device.read(self)

    def write(self, value: ua.DataValue) -> ua.StatusCode:
        return self.device.write(self, value)

    def data_value(self, value: Any) -> ua.DataValue:
        converted = to_opcua(self.variable, value)
        if converted is None and self.vtype != ua.VariantType.String:  # a number or Boolean with no value
            return ua.DataValue(StatusCode=ua.StatusCode(_BAD.BadNoData))
        stamped = self.stamped
        if stamped is not None:
            if stamped[0] == value:
                written = stamped[1]
                return ua.DataValue(ua.Variant(converted, self.vtype),
                                    SourceTimestamp=written.SourceTimestamp or datetime.now(UTC),
                                    SourcePicoseconds=written.SourcePicoseconds if written.SourceTimestamp else None,
                                    ServerTimestamp=written.ServerTimestamp, ServerPicoseconds=written.ServerPicoseconds)
            self.stamped = None  # (the device's value has changed since: its own time again)
        return ua.DataValue(ua.Variant(converted, self.vtype), SourceTimestamp=datetime.now(UTC))


class _DeviceNode:
    """One device's object: its variables, watch, methods and fault events."""

    def __init__(self, facade: OpcuaFacade, device: Device, node: Any) -> None:
        self.facade, self.device, self.node = facade, device, node
        self.bound: dict[str, _Bound] = {}
        self.generators: list[EventGenerator] = []
        self.watch: PointWatch | None = None
        self._pending: dict[str, Any] = {}
        self._events: list[tuple[str, str, bool, int, int]] = []
        self._tasks: dict[str, asyncio.Task[None]] = {}  # "values" / "events": the one draining each
        self._undo: list[Callable[[], None]] = []
        self._sample_due = False

    # -- values ---------------------------------------------------------------------------
    def read(self, bound: _Bound) -> ua.DataValue:
        if not bound.variable.readable:
            return ua.DataValue(StatusCode=ua.StatusCode(_BAD.BadNotReadable))
        try:
            return bound.data_value(self.device.read(bound.variable.point))
        except (UnknownName, ValueError, LookupError, ArithmeticError):
            return ua.DataValue(StatusCode=ua.StatusCode(_BAD.BadNoData))

    def write(self, bound: _Bound, value: ua.DataValue) -> ua.StatusCode:
        variable = bound.variable
        if not variable.writable:
            return ua.StatusCode(_BAD.BadNotWritable)
        variant = value.Value
        if variant is None or variant.Value is None:
            return ua.StatusCode(_BAD.BadTypeMismatch)
        try:
            self.device.set(variable.point, from_opcua(variable, variant.VariantType.name, variant.Value))
        except TypeMismatch:
            return ua.StatusCode(_BAD.BadTypeMismatch)
        except ReadOnlyName:
            return ua.StatusCode(_BAD.BadNotWritable)
        except (BadValue, ValueError):
            return ua.StatusCode(_BAD.BadOutOfRange)
        except Exception:  # noqa: BLE001 - the device's failure, not the server's
            logging.getLogger(__name__).exception("%s: writing %s failed", self.device.name, variable.point)
            return ua.StatusCode(_BAD.BadInternalError)
        bound.stamped = None
        if (value.SourceTimestamp or value.ServerTimestamp) and variable.readable:  # its time is the writer's
            with contextlib.suppress(UnknownName, ValueError, LookupError, ArithmeticError):  # (as read: no data)
                bound.stamped = (self.device.read(variable.point), value)
        self.sample_soon()  # subscribers see the write (and what it moved) at once
        return ua.StatusCode()

    def sample_soon(self) -> None:
        """One extra sample of the points after this loop turn (one for a batch of writes)."""
        if self.watch is not None and not self._sample_due:
            self._sample_due = True
            asyncio.get_running_loop().call_soon(self._sample)

    def _sample(self) -> None:
        self._sample_due = False
        if self.watch is not None:
            self.watch.sample()

    def changed(self, changes: dict[str, Any]) -> None:
        """The watch's listener: the changed values go into the address space (in a task)."""
        self._pending.update(changes)
        self._drain("values", self._flush)

    def _drain(self, what: str, work: Callable[[], Any]) -> None:
        """Run ``work()`` (a coroutine emptying a queue) in the server's loop unless it runs
        already: one task per queue keeps the order of values and events."""
        loop = self.facade.loop
        assert loop is not None, "the server has not started"

        def start() -> None:
            task = self._tasks.get(what)
            if task is None or task.done():
                self._tasks[what] = loop.create_task(work())

        try:
            here = asyncio.get_running_loop() is loop
        except RuntimeError:
            here = False
        if here:
            start()
        else:  # a device used from another thread (not the runtime's way, but not to break it)
            loop.call_soon_threadsafe(start)

    async def _flush(self) -> None:
        server = self.facade.server
        while self._pending:
            changes, self._pending = self._pending, {}
            for name, value in changes.items():
                bound = self.bound.get(name)
                if bound is not None:
                    await server.write_attribute_value(bound.node_id, bound.data_value(value))

    # -- faults and power ---------------------------------------------------------------------
    # (DeviceMethods has checked the object, the number and the types of the arguments)
    async def fault_method(self, parent: ua.NodeId, kind: ua.Variant, active: ua.Variant) -> Any:
        try:
            run(self.facade.runtime, rq.SwitchFault(self.device.name, kind.Value, active.Value))
        except (UnknownName, ValueError):  # not one of FaultKinds: out of range (Part 4, Table 68)
            return call_result(_BAD.BadInvalidArgument, [_BAD.BadOutOfRange, _BAD.Good])
        return []

    async def power_cycle_method(self, parent: ua.NodeId, wipe: ua.Variant) -> Any:
        run(self.facade.runtime, rq.PowerCycle(self.device.name, bool(wipe.Value)))
        self.sample_soon()
        return []

    def fault_switched(self, kind: str, active: bool) -> None:
        self._emit(f"{self.device.name}: fault {kind} {'on' if active else 'off'}", kind, active, 0, 0)

    def model_fault(self, axis: int = 1, code: int = 0x1000) -> None:
        self._emit(f"{self.device.name}: fault on axis {axis}, code {code:04X}h", "", True, axis, code)

    def _emit(self, message: str, kind: str, active: bool, axis: int, code: int) -> None:
        self._events.append((message, kind, active, int(axis), int(code)))
        self._drain("events", self._send_events)

    async def _send_events(self) -> None:
        """The queued fault events, one after the other (the generators' event objects are
        reused: filled just before each trigger)."""
        while self._events:
            message, kind, active, axis, code = self._events.pop(0)
            for generator in self.generators:
                event = generator.event
                event.FaultKind, event.Active, event.Axis, event.Code = kind, active, axis, code
                event.Severity = 700 if active else 300
                await generator.trigger(message=message)

    def close(self) -> None:
        if self.watch is not None:
            self.watch.stop()
        for undo in self._undo:
            undo()
        for task in self._tasks.values():
            task.cancel()


class OpcuaFacade:
    """The OPC UA server of a plant: ``devices`` under ``Objects``, at ``endpoint``.

    ``period`` is how often (seconds of device time) each device's points are sampled for
    subscriptions."""

    def __init__(self, devices: Sequence[Device], endpoint: str = DEFAULT_ENDPOINT, *, runtime: Runtime,
                 period: float = 0.1, name: str = "devsim") -> None:
        if not period > 0:
            raise ValueError("an OPC UA sampling period is a positive number of seconds")
        self.devices, self.endpoint, self.period, self.name = list(devices), endpoint, period, name
        self.runtime = runtime  # the Fault and PowerCycle methods run its control ops
        self.server = FacadeServer(runtime.clock)  # (monitored items' sampling intervals: device time)
        self.bound: dict[ua.NodeId, _Bound] = {}
        self.nodes: dict[str, _DeviceNode] = {}
        self.namespace = 0
        self.url = endpoint
        self.loop: asyncio.AbstractEventLoop | None = None

    async def start(self) -> str:
        """Build the address space and listen; returns the endpoint URL (with the port the
        system chose when the endpoint's port is 0)."""
        server = self.server
        self.loop = asyncio.get_running_loop()
        await server.init()
        await self._identify(server)
        server.set_endpoint(self.endpoint)
        server.set_server_name(f"devsim {self.name}")
        server.set_security_policy([ua.SecurityPolicyType.NoSecurity])  # a lab's simulator: no certificates
        server.set_identity_tokens([ua.AnonymousIdentityToken])  # and no user names
        self.namespace = await server.register_namespace(NAMESPACE)
        iserver = server.iserver
        iserver.attribute_service = PointAttributes(iserver.aspace, self.bound)
        iserver.method_service.stop()
        iserver.method_service = DeviceMethods(iserver.aspace)
        iserver.view_service = NodeView(iserver.aspace)
        event_type = await server.create_custom_event_type(
            self.namespace, "DeviceFaultEventType", ua.ObjectIds.BaseEventType,
            [("FaultKind", ua.VariantType.String), ("Active", ua.VariantType.Boolean),
             ("Axis", ua.VariantType.Int32), ("Code", ua.VariantType.Int32)])
        for device in self.devices:
            await self._add_device(device, event_type)
        quiet = logging.getLogger("asyncua.server.server")  # a port in use: the caller's one line,
        level = quiet.level  # not asyncua's logged traceback
        quiet.setLevel(logging.CRITICAL)
        try:
            await server.start()
        finally:
            quiet.setLevel(level)
        bserver = server.bserver
        parsed = urlparse(self.endpoint)
        if bserver is not None and parsed.port == 0:
            self.url = f"opc.tcp://{parsed.hostname}:{bserver.port}{parsed.path}"
        for node in self.nodes.values():
            if node.watch is not None:
                node.watch.start()
        return self.url

    async def _identify(self, server: FacadeServer) -> None:
        """The server says it is devsim (Part 5 6.3.1 ServerArray, NamespaceArray[1] = its
        ApplicationUri; 12.4 BuildInfo), not asyncua's "FreeOpcUa Python Server" 1.0pre: a client's
        server list and diagnostics name the simulator and its version."""
        server.product_uri, server.manufacturer_name = NAMESPACE, "devsim"  # (its endpoints' description)
        await server.set_application_uri(f"urn:devsim:server:{quote(self.name)}")  # (a plant's name may hold spaces)
        await server.get_node(ua.NodeId(ua.ObjectIds.Server_ServerArray)).write_value([server.get_application_uri()])
        built = datetime.fromtimestamp(Path(devsim.__file__).stat().st_mtime, UTC)  # (the installed package)
        await server.set_build_info(server.product_uri, server.manufacturer_name, f"devsim {self.name}", devsim.__version__,
                                    devsim.__version__, built)

    async def _add_device(self, device: Device, event_type: Any) -> None:
        ns = self.namespace
        objects = self.server.nodes.objects
        obj = await objects.add_object(ua.NodeId(device.name, ns), ua.QualifiedName(device.name, ns))
        await obj.write_attribute(ua.AttributeIds.Description,
                                  ua.DataValue(ua.Variant(ua.LocalizedText(device.description or device.kind))))
        node = _DeviceNode(self, device, obj)
        self.nodes[device.name] = node
        await obj.add_property(ua.NodeId(f"{device.name}#Kind", ns), ua.QualifiedName("Kind", ns),
                               device.kind, ua.VariantType.String)
        fault_kinds = await obj.add_property(ua.NodeId(f"{device.name}#FaultKinds", ns),
                                             ua.QualifiedName("FaultKinds", ns), device.faults.names(),
                                             ua.VariantType.String)
        await fault_kinds.write_value_rank(ua.ValueRank.OneDimension)  # an array of names (Part 3, 5.6.2)
        await fault_kinds.write_array_dimensions([0])  # of any length
        await obj.add_method(ua.NodeId(f"{device.name}#Fault", ns), ua.QualifiedName("Fault", ns), node.fault_method,
                             [_argument("kind", ua.VariantType.String, "a declared fault (FaultKinds)"),
                              _argument("active", ua.VariantType.Boolean, "on (true) or off")], [])
        await obj.add_method(ua.NodeId(f"{device.name}#PowerCycle", ns), ua.QualifiedName("PowerCycle", ns),
                             node.power_cycle_method,
                             [_argument("wipe", ua.VariantType.Boolean, "erase non-volatile memory first")], [])
        rows = variables(device.name, device.points)
        items = [self._variable_item(obj.nodeid, row) for row in rows]
        results = await self.server.iserver.isession.add_nodes(items)
        units = []
        for row, result in zip(rows, results, strict=True):
            result.StatusCode.check()
            bound = _Bound(node, row, result.AddedNodeId)
            node.bound[row.point] = self.bound[result.AddedNodeId] = bound
            if row.unit:
                units.append(_unit_item(result.AddedNodeId, row.unit))
            if not row.readable:  # a write-only point: monitored, it tells so (Part 4, 5.12.2)
                await self.server.write_attribute_value(result.AddedNodeId, _NOT_READABLE)
        for result in await self.server.iserver.isession.add_nodes(units):
            result.StatusCode.check()
        # fault events, from the device object and from the Server object
        for emitting in (obj.nodeid, ua.NodeId(ua.ObjectIds.Server)):
            generator = await self.server.get_event_generator(event_type, emitting)
            generator.event.SourceNode, generator.event.SourceName = obj.nodeid, device.name
            node.generators.append(generator)
        node._undo.append(device.model.listen("fault_switched", node.fault_switched))
        node._undo.append(device.model.listen("fault", node.model_fault))
        readable = [row.point for row in rows if row.readable]
        node.watch = PointWatch(device, node.changed, names=readable, period=self.period)

    def _variable_item(self, parent: ua.NodeId, row: Variable) -> ua.AddNodesItem:
        item = ua.AddNodesItem()
        item.RequestedNewNodeId = ua.NodeId(row.node_id, self.namespace)
        item.BrowseName = ua.QualifiedName(row.point, self.namespace)
        item.NodeClass = ua.NodeClass.Variable
        item.ParentNodeId = parent
        item.ReferenceTypeId = ua.NodeId(ua.ObjectIds.HasComponent)
        item.TypeDefinition = ua.NodeId(ua.ObjectIds.BaseDataVariableType)
        attrs = ua.VariableAttributes()
        attrs.DisplayName = ua.LocalizedText(row.point)
        attrs.Description = ua.LocalizedText(row.description)
        vtype = ua.VariantType[row.data_type]
        attrs.DataType = ua.NodeId(vtype.value)
        attrs.Value = ua.Variant(ua.get_default_value(vtype), vtype)
        attrs.ValueRank = ua.ValueRank.Scalar
        # sampled every period for changes (PointWatch), not "continuously" (0; Part 3, 5.6.2)
        attrs.MinimumSamplingInterval = 1000 * self.period
        access = (_READ if row.readable else 0) | (_WRITE if row.writable else 0)
        attrs.AccessLevel = attrs.UserAccessLevel = access
        attrs.WriteMask = attrs.UserWriteMask = 0
        attrs.Historizing = False
        item.NodeAttributes = attrs
        return item

    async def stop(self) -> None:
        for node in self.nodes.values():
            node.close()
        await self.server.stop()


def _argument(name: str, vtype: ua.VariantType, doc: str) -> ua.Argument:
    argument = ua.Argument()
    argument.Name = name
    argument.DataType = ua.NodeId(vtype.value)
    argument.ValueRank = ua.ValueRank.Scalar
    argument.Description = ua.LocalizedText(doc)
    return argument


def _unit_item(parent: ua.NodeId, unit: str) -> ua.AddNodesItem:
    """The ``EngineeringUnits`` property (EUInformation) of a variable."""
    namespace_uri, unit_id, display, description = eu_information(unit)
    info = ua.EUInformation(NamespaceUri=namespace_uri, UnitId=unit_id, DisplayName=ua.LocalizedText(display),
                            Description=ua.LocalizedText(description))
    item = ua.AddNodesItem()
    item.RequestedNewNodeId = ua.NodeId(NamespaceIndex=parent.NamespaceIndex)
    item.BrowseName = ua.QualifiedName("EngineeringUnits", 0)
    item.NodeClass = ua.NodeClass.Variable
    item.ParentNodeId = parent
    item.ReferenceTypeId = ua.NodeId(ua.ObjectIds.HasProperty)
    item.TypeDefinition = ua.NodeId(ua.ObjectIds.PropertyType)
    attrs = ua.VariableAttributes()
    attrs.DisplayName = ua.LocalizedText("EngineeringUnits")
    attrs.DataType = ua.NodeId(ua.ObjectIds.EUInformation)
    attrs.Value = ua.Variant(info, ua.VariantType.ExtensionObject)
    attrs.ValueRank = ua.ValueRank.Scalar
    attrs.AccessLevel = attrs.UserAccessLevel = _READ
    item.NodeAttributes = attrs
    return item


async def start_opcua(runtime: Runtime, devices: Sequence[Device], spec: str | None = None, *, period: float = 0.1,
                      name: str = "devsim") -> OpcuaFacade:
    """Serve ``devices`` on one OPC UA server in ``runtime``'s loop (call it there): ``spec`` is
    ``[[HOST:]PORT]`` or an ``opc.tcp://`` URL (default :data:`DEFAULT_ENDPOINT`, loopback unless
    a host is named).  The server stops with the runtime; its URL is ``runtime.ports["opcua"]``."""
    library_log.limit("asyncua", "opcua")  # (a traceback for every request it cannot decode, a line for each bad one)
    facade = OpcuaFacade(devices, endpoint_url(spec), runtime=runtime, period=period, name=name)
    await facade.start()
    runtime.add_closer(facade.stop)
    runtime.ports["opcua"] = facade.url
    return facade
