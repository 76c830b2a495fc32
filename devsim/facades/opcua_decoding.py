"""Requests the OPC UA facade cannot decode (and a few it can), answered with OPC UA Part 4's
status codes.

asyncua decodes a request's parameters just before it serves them; a value it cannot decode (an
enumeration's value out of its range, a body cut short, text that is not UTF-8) escapes as an
exception and is answered ``Bad_InternalError``, with a logged traceback.  :class:`FacadeServer`
processes each connection with :class:`RequestDecoding`, which answers such a request with a
ServiceFault whose status is Part 4's (v1.04):

* ``Bad_TimestampsToReturnInvalid`` for a ``timestampsToReturn`` that is not one of the
  TimestampsToReturn enumeration's (7.40: Source, Server, Both, Neither): the service result of
  Read (5.10.2), HistoryRead (5.10.3), CreateMonitoredItems (5.12.2) and ModifyMonitoredItems
  (5.12.3).  asyncua decodes 4 (its ``Invalid``) and no other value outside 0..3; the Read service
  (:class:`devsim.facades.opcua_services.PointAttributes`) refuses 4, this module 4 for the others;
* ``Bad_MonitoringModeInvalid`` for SetMonitoringMode's ``monitoringMode`` (5.12.4, Table 76);
* ``Bad_DecodingError`` for anything else that does not decode (7.34.2, the common service results:
  "decoding halted because of invalid data in the stream"), an enumeration inside an operation's
  item (a BrowseDescription's browseDirection, a MonitoredItemCreateRequest's monitoringMode)
  included: asyncua decodes a request whole, so one bad item fails it all.

Requests that decode but that asyncua answers otherwise than Part 4 are answered here too:

* ``Bad_NothingToDo`` for a request whose list of operations is empty (NodesToRead, NodesToWrite,
  MethodsToCall, ItemsToCreate ...: each service's service results; asyncua: Good, no results);
* BrowseNext (5.8.3), which asyncua does not serve, from the connection's continuation points
  (:class:`devsim.facades.opcua_services.ContinuationPoints`, which Browse fills);
* ``Bad_ServiceUnsupported`` for a service asyncua does not serve (QueryFirst, HistoryUpdate,
  Cancel ...; asyncua: Bad_UserAccessDenied, as if the user were not allowed it).

:class:`FacadeServer` also gives asyncua's server the facade's subscriptions
(:mod:`devsim.facades.opcua_monitoring`) and HistoryRead
(:class:`devsim.facades.opcua_services.NodeHistory`).

What asyncua logs about it (``sending service fault response: …``) goes through
:mod:`devsim.facades.library_log`, rate-limited, as any of its lines.
"""

from __future__ import annotations

import time
from typing import Any

from asyncua import Server, ua
from asyncua.common.utils import Buffer, ServiceError
from asyncua.crypto.permission_rules import ADMIN_TYPES, USER_TYPES
from asyncua.server.binary_server_asyncio import BinaryServer, OPCUAProtocol
from asyncua.server.uaprocessor import UaProcessor
from asyncua.ua.ua_binary import from_binary, get_safe_type_hints, struct_from_binary

from devsim.core.clock import Clock
from devsim.facades.opcua_monitoring import QUEUE_SIZE, Subscriptions
from devsim.facades.opcua_services import CONTINUATION, ContinuationPoints, NodeHistory

__all__ = ["FacadeServer", "RequestDecoding", "undecodable"]

_BAD = ua.StatusCodes
_TIMESTAMPS = frozenset({ua.TimestampsToReturn.Source, ua.TimestampsToReturn.Server, ua.TimestampsToReturn.Both,
                         ua.TimestampsToReturn.Neither})
#: a parameter of an enumeration the request names a status for, when its value is not one of it
_ENUMERATIONS: dict[Any, int] = {
    ua.TimestampsToReturn: _BAD.BadTimestampsToReturnInvalid,
    ua.MonitoringMode: _BAD.BadMonitoringModeInvalid,
}
#: the services asyncua serves (those its permission rules name), and BrowseNext, served here
_SERVED = frozenset(ua.NodeId(typeid) for typeid in (*USER_TYPES, *ADMIN_TYPES))
_BROWSE_NEXT = ua.NodeId(ua.ObjectIds.BrowseNextRequest_Encoding_DefaultBinary)
#: the services of a list of operations (Part 4: an empty list is Bad_NothingToDo, the whole request)
_OPERATIONS = {ua.NodeId(getattr(ua.ObjectIds, f"{name}Request_Encoding_DefaultBinary")): getattr(ua, f"{name}Parameters")
               for name in ("Read", "Write", "Browse", "TranslateBrowsePathsToNodeIds", "Call", "HistoryRead",
                            "CreateMonitoredItems", "ModifyMonitoredItems", "DeleteMonitoredItems", "SetMonitoringMode",
                            "SetPublishingMode", "DeleteSubscriptions", "TransferSubscriptions", "RegisterNodes",
                            "UnregisterNodes")}
#: each one's list of operations (its one list field)
_LISTS = {kind: next(name for name, spec in kind.__dataclass_fields__.items() if spec.default_factory is list)
          for kind in _OPERATIONS.values()}
#: the services asyncua serves whose timestampsToReturn it does not check (Read's: PointAttributes; all
#: of them in _OPERATIONS)
_TIMESTAMPED = {ua.NodeId(getattr(ua.ObjectIds, f"{name}Request_Encoding_DefaultBinary")): getattr(ua, f"{name}Parameters")
                for name in ("HistoryRead", "CreateMonitoredItems", "ModifyMonitoredItems")}


def _decodes(kind: Any, body: Buffer) -> bool:
    try:
        from_binary(kind, body)
    except Exception:  # noqa: BLE001 - whatever asyncua's decoders raise on bad data
        return False
    return True


def _fields(kind: Any) -> list[str]:
    """The names of the fields of one of asyncua's ``ua`` structures, in their order on the wire
    (its dataclass fields, as asyncua's own encoding reads them; a union's class variable, with its
    underscore, is none)."""
    return [name for name in kind.__dataclass_fields__ if not name.startswith("_")]


def undecodable(typeid: ua.NodeId, body: Buffer) -> int | None:
    """The status code for a request of type ``typeid`` whose parameters (``body``, after its
    RequestHeader) do not decode; None when they do (or the service is not one asyncua knows)."""
    request = ua.extension_objects_by_typeid.get(typeid)
    if request is None:
        return None
    hints = get_safe_type_hints(request, {"ua": ua})
    for field in _fields(request)[2:]:  # after TypeId and RequestHeader
        kind = hints[field]
        if not hasattr(kind, "__dataclass_fields__") or "Encoding" in _fields(kind):
            if not _decodes(kind, body):
                return _BAD.BadDecodingError
            continue
        inner = get_safe_type_hints(kind, {"ua": ua})  # the Parameters: which of them fails
        for parameter in _fields(kind):
            if not _decodes(inner[parameter], body):
                return _ENUMERATIONS.get(inner[parameter], _BAD.BadDecodingError)
    return None


class RequestDecoding(UaProcessor):
    """asyncua's processing of a connection's messages, with Part 4's status code for a request
    whose parameters do not decode (asyncua: Bad_InternalError) and for a timestampsToReturn out of
    the enumeration in the services that take one; BrowseNext served from the connection's
    continuation points (Part 4, 5.8.3), and Bad_ServiceUnsupported for a service asyncua does
    not serve (asyncua: Bad_UserAccessDenied, as if the user were not allowed it)."""

    def __init__(self, *args: Any) -> None:
        super().__init__(*args)
        self.continuation = ContinuationPoints()  # this connection's Browse continuation points

    async def _process_message(self, typeid: ua.NodeId, requesthdr: ua.RequestHeader, seqhdr: Any,
                               body: Buffer) -> Any:
        session = self.session
        if session is not None and session.is_activated():
            if typeid == _BROWSE_NEXT:
                return self._browse_next(requesthdr, seqhdr, body)
            if typeid not in _SERVED:  # asyncua refused these as Bad_UserAccessDenied
                raise ServiceError(_BAD.BadServiceUnsupported)
        token = CONTINUATION.set(self.continuation)  # (Browse pages with them)
        try:
            return await self._decoded(typeid, requesthdr, seqhdr, body)
        finally:
            CONTINUATION.reset(token)

    def _browse_next(self, requesthdr: ua.RequestHeader, seqhdr: Any, body: Buffer) -> bool:
        """BrowseNext (Part 4, 5.8.3), which asyncua does not serve."""
        try:
            params = struct_from_binary(ua.BrowseNextParameters, body)
        except Exception:  # noqa: BLE001 - whatever asyncua's decoders raise on bad data
            raise ua.UaStatusCodeError(_BAD.BadDecodingError) from None
        if not params.ContinuationPoints:
            raise ServiceError(_BAD.BadNothingToDo)
        self.session_last_activity = time.monotonic()  # as asyncua does for every request of a session
        self.session.touch()
        response = ua.BrowseNextResponse()
        response.Parameters.Results = self.continuation.browse_next(params)
        self.send_response(requesthdr.RequestHandle, seqhdr, response)
        return True

    async def _decoded(self, typeid: ua.NodeId, requesthdr: ua.RequestHeader, seqhdr: Any, body: Buffer) -> Any:
        parameters = body.copy()
        kind = _OPERATIONS.get(typeid)
        if kind is not None and self.session is not None and self.session.is_activated():
            try:  # (an undecodable one: answered below, as asyncua fails to decode it)
                params = struct_from_binary(kind, parameters.copy())
            except Exception:  # noqa: BLE001, S110 - asyncua's decoding fails the same way next
                pass
            else:
                if not getattr(params, _LISTS[kind]):  # no operation at all (asyncua: Good, no results)
                    raise ua.UaStatusCodeError(_BAD.BadNothingToDo)
                if typeid in _TIMESTAMPED and params.TimestampsToReturn not in _TIMESTAMPS:
                    raise ua.UaStatusCodeError(_BAD.BadTimestampsToReturnInvalid)
        try:
            return await super()._process_message(typeid, requesthdr, seqhdr, body)
        except (ServiceError, ua.UaStatusCodeError):  # a status code already (Bad_UserAccessDenied among them)
            raise
        except Exception:
            status = undecodable(typeid, parameters)
            if status is None:  # it decodes: the failure is the server's own (Bad_InternalError)
                raise
            raise ua.UaStatusCodeError(status) from None


class _Connection(OPCUAProtocol):
    def connection_made(self, transport: Any) -> None:
        super().connection_made(transport)
        if self.processor is not None:  # (None: refused, at max_connections)
            self.processor = RequestDecoding(self.iserver, self.transport, self.limits)
            self.processor.set_policies(self.policies)


class _Listener(BinaryServer):
    def _make_protocol(self) -> OPCUAProtocol:
        return _Connection(iserver=self.iserver, policies=self._policies, clients=self.clients,
                           closing_tasks=self.closing_tasks, limits=self.limits)


class FacadeServer(Server):
    """asyncua's server, its connections processed by :class:`RequestDecoding`, its monitored items
    checked by :class:`devsim.facades.opcua_monitoring.ItemChecks`, its Browse paged with
    continuation points (:class:`devsim.facades.opcua_services.ContinuationPoints`)."""

    def __init__(self, clock: Clock | None = None) -> None:
        super().__init__()
        iserver = self.iserver  # (before init: nothing holds the service asyncua made but its session)
        iserver.subscription_service = iserver.isession.subscription_service = Subscriptions(
            iserver.aspace, iserver, clock)
        iserver.max_monitored_item_queue_size = QUEUE_SIZE  # (read by each subscription created)
        iserver.history_manager = NodeHistory(iserver)

    async def init(self, shelf_file: Any = None) -> None:
        """asyncua's ``Server.init``, and the ServerCapabilities' MaxBrowseContinuationPoints: the
        continuation points a connection keeps (Part 5, 6.3.2)."""
        await super().init(shelf_file)
        await self.write_attribute_value(ua.NodeId(ua.ObjectIds.Server_ServerCapabilities_MaxBrowseContinuationPoints),
                                         ua.DataValue(ua.Variant(ContinuationPoints.MOST, ua.VariantType.UInt16)))

    async def start(self) -> None:
        """asyncua's ``Server.start`` with :class:`_Listener` for its BinaryServer (and no
        certificate to check: the facade serves without security)."""
        await self._setup_server_nodes()
        await self.iserver.start()
        try:
            host, port = self._get_bind_socket_info()
            self.bserver = _Listener(self.iserver, host, port, self.limits)
            self.bserver.set_policies(self._policies)
            await self.bserver.start()
        except Exception:
            await self.iserver.stop()
            raise
