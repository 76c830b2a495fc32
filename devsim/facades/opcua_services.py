"""The Attribute and Method service sets of the OPC UA facade (OPC UA Part 4, 5.10 and 5.11):
asyncua's services, with the point variables read from and written to their devices and the
status codes Part 4 gives where asyncua answers otherwise.

* :class:`PointAttributes` (Part 4, 5.10.2 Read, 5.10.4 Write).  A point variable's Value is
  read from and written to its device (:class:`PointNode`).  A read of any Value honours the
  request's ``timestampsToReturn`` (Source, Server, Both, Neither) and ``indexRange`` (7.27: a
  substring of a String, a slice of an array; ``Bad_IndexRangeInvalid`` for a range of invalid
  syntax, ``Bad_IndexRangeNoData`` for one that selects nothing, as on a scalar number; the same
  for any other attribute: a range on a DisplayName selects nothing), and a
  request with a negative ``maxAge`` or an invalid ``timestampsToReturn`` is a service fault
  (``Bad_MaxAgeInvalid``, ``Bad_TimestampsToReturnInvalid``).  asyncua ignores all three.  A
  ``dataEncoding`` is refused unless it is ``Default Binary`` for the Value of a Structure
  (:func:`encoding_refusal`: ``Bad_DataEncodingInvalid`` / ``Bad_DataEncodingUnsupported``, Part 4
  7.34; asyncua ignored it).  A write of any node by a client
  answers, in this order: ``Bad_NodeIdUnknown`` for a node the server does not have,
  ``Bad_AttributeIdInvalid`` for an attribute the node does not have, ``Bad_NotWritable`` when
  the node's AccessLevel (Value) or WriteMask (any other attribute) does not allow writing,
  ``Bad_UserAccessDenied`` when only its UserAccessLevel / UserWriteMask does not, and for a
  point's Value ``Bad_WriteNotSupported`` when an IndexRange or a status code is written with it
  (Table 61: the server does not support that combination).  asyncua answers
  ``Bad_UserAccessDenied`` for all of these.
* :class:`NodeHistory` (Part 4, 5.10.3 HistoryRead): ``Bad_NodeIdUnknown`` for a node the server
  does not have, ``Bad_HistoryOperationUnsupported`` for one that keeps no history (asyncua: Good,
  no data).
* :class:`NodeView` (Part 4, 5.8.2 Browse, 5.8.4 TranslateBrowsePathsToNodeIds): ``Bad_NodeIdUnknown``
  for a node (a path's startingNode) the server does not have (asyncua: ``Bad_NodeIdInvalid``, which
  Part 4 keeps for a NodeId of invalid syntax); no more references a node than the client's
  ``requestedMaxReferencesPerNode``, the rest behind a continuation point for BrowseNext (5.8.3,
  :class:`ContinuationPoints`; asyncua has no BrowseNext and sent every reference).
* :class:`DeviceMethods` (Part 4, 5.11.2 Call, Tables 67 and 68): ``Bad_NodeIdUnknown`` for an
  object the server does not have, ``Bad_NodeIdInvalid`` for a node that is not an object,
  ``Bad_MethodInvalid`` for a method that is not a component of that object,
  ``Bad_ArgumentsMissing`` / ``Bad_TooManyArguments`` against the method's InputArguments, and
  ``Bad_InvalidArgument`` with a ``Bad_TypeMismatch`` in ``inputArgumentResults`` for each
  argument whose type is not the declared built-in one.  asyncua runs the method of any object
  on any other and answers a wrong argument count with ``Bad_UnexpectedError``.
"""

from __future__ import annotations

import os
import re
from collections.abc import Mapping
from contextvars import ContextVar
from datetime import UTC, datetime
from typing import Any, Protocol

from asyncua import ua
from asyncua.crypto.permission_rules import User, UserRole
from asyncua.server.address_space import AddressSpace, AttributeService, MethodService, ViewService
from asyncua.server.history import HistoryManager

__all__ = ["CONTINUATION", "ContinuationPoints", "DeviceMethods", "NodeHistory", "NodeView", "PointAttributes", "PointNode", "call_result", "derives", "encoding_refusal",
           "index_range", "shaped"]

_BAD = ua.StatusCodes
_ADMIN = User(role=UserRole.Admin)  # asyncua's default for a write from inside the server
_WRITE = ua.AccessLevel.CurrentWrite.mask
_OBJECTS = (ua.NodeClass.Object, ua.NodeClass.ObjectType)
_STRUCTURE = ua.NodeId(ua.ObjectIds.Structure)
_HAS_SUBTYPE = ua.NodeId(ua.ObjectIds.HasSubtype)
_DEFAULT_BINARY = ua.QualifiedName("Default Binary", 0)
_BUILT_IN = range(1, 26)  # ns=0 DataType ids of the built-in types (Part 6, 5.1.2): a Variant's type


class PointNode(Protocol):
    """A point variable as the attribute service sees it (``_Bound`` in :mod:`devsim.facades.opcua`)."""

    def read(self) -> ua.DataValue: ...

    def write(self, value: ua.DataValue) -> ua.StatusCode: ...


def _status(code: int) -> ua.StatusCode:
    return ua.StatusCode(code)


class PointAttributes(AttributeService):
    """asyncua's attribute service, with the point variables' Values read from and written to
    their devices, and Part 4's status codes for what a client may not write."""

    def __init__(self, aspace: AddressSpace, points: Mapping[ua.NodeId, PointNode]) -> None:
        super().__init__(aspace)
        self.points = points

    def read(self, params: ua.ReadParameters) -> list[ua.DataValue]:
        if params.MaxAge < 0:
            raise ua.UaStatusCodeError(_BAD.BadMaxAgeInvalid)
        if params.TimestampsToReturn not in _TIMESTAMPS:
            raise ua.UaStatusCodeError(_BAD.BadTimestampsToReturnInvalid)
        results = super().read(params)
        for index, item in enumerate(params.NodesToRead):
            if not results[index].StatusCode.is_bad() and (refused := encoding_refusal(self._aspace, item)) is not None:
                results[index] = ua.DataValue(StatusCode=_status(refused))
            elif item.AttributeId == ua.AttributeIds.Value:
                point = self.points.get(item.NodeId)
                value = point.read() if point is not None else results[index]
                results[index] = shaped(value, params.TimestampsToReturn, item.IndexRange)
            elif item.IndexRange and results[index].StatusCode.is_good():
                part = _range_of(results[index].Value, item.IndexRange)  # (asyncua ignored it)
                results[index] = ua.DataValue(StatusCode=_status(part)) if isinstance(part, int) else ua.DataValue(part)
        return results

    async def write(self, params: ua.WriteParameters, user: User = _ADMIN) -> list[ua.StatusCode]:
        results: list[ua.StatusCode] = []
        for item in params.NodesToWrite:
            refused = self._refusal(item, user)
            if refused is not None:
                results.append(_status(refused))
            elif (point := self.points.get(item.NodeId)) is not None and item.AttributeId == ua.AttributeIds.Value:
                results.append(point.write(item.Value))
            else:
                results.extend(await super().write(ua.WriteParameters(NodesToWrite=[item]), user))
        return results

    def _attribute(self, node_id: ua.NodeId, attribute: ua.AttributeIds) -> Any:
        data_value = self._aspace.read_attribute_value(node_id, attribute)
        return data_value.Value.Value if data_value.StatusCode.is_good() and data_value.Value is not None else None

    def _refusal(self, item: ua.WriteValue, user: User) -> int | None:
        """The status code a write is refused with before it reaches the node (None: none)."""
        node_id, attribute = item.NodeId, item.AttributeId
        if node_id not in self._aspace:
            return _BAD.BadNodeIdUnknown
        if attribute not in self._aspace[node_id].attributes:
            return _BAD.BadAttributeIdInvalid
        if user.role == UserRole.Admin:  # the server itself
            return None
        if attribute == ua.AttributeIds.Value:
            allowed = self._attribute(node_id, ua.AttributeIds.AccessLevel) or 0
            user_allowed = self._attribute(node_id, ua.AttributeIds.UserAccessLevel) or 0
            bit = _WRITE
        else:  # Part 3, 5.2.7: WriteMask, a bit per attribute (AttributeWriteMask)
            allowed = self._attribute(node_id, ua.AttributeIds.WriteMask) or 0
            user_allowed = self._attribute(node_id, ua.AttributeIds.UserWriteMask) or 0
            mask = ua.AttributeWriteMask.__members__.get(ua.AttributeIds(attribute).name)
            bit = int(mask) if mask is not None else 0
        if not allowed & bit:
            return _BAD.BadNotWritable
        if not user_allowed & bit:
            return _BAD.BadUserAccessDenied
        if node_id in self.points and attribute == ua.AttributeIds.Value:
            value = item.Value
            if item.IndexRange or (value.StatusCode is not None and not value.StatusCode.is_good()):
                return _BAD.BadWriteNotSupported
        return None


_TIMESTAMPS = (ua.TimestampsToReturn.Source, ua.TimestampsToReturn.Server, ua.TimestampsToReturn.Both,
               ua.TimestampsToReturn.Neither)
_RANGE = re.compile(r"(\d+)(?::(\d+))?", re.ASCII)  # (without ASCII, \d is the digits of every script)


def index_range(text: str) -> list[tuple[int, int]] | None:
    """A NumericRange (Part 4, 7.27) as (first, last) per dimension; None: invalid syntax."""
    dimensions = []
    for part in text.split(","):
        match = _RANGE.fullmatch(part)
        if match is None:
            return None
        first = int(match[1])
        last = first if match[2] is None else int(match[2])
        if match[2] is not None and last <= first:  # "5:5" and "7:5" are invalid
            return None
        dimensions.append((first, last))
    return dimensions


def _range_of(variant: ua.Variant | None, text: str) -> ua.Variant | int:
    """The part of a value an index range selects, or the status code why none."""
    dimensions = index_range(text)
    if dimensions is None:
        return _BAD.BadIndexRangeInvalid
    value = variant.Value if variant is not None else None
    if variant is not None and isinstance(value, list | tuple) and len(dimensions) == 2 \
            and all(isinstance(item, str | bytes) for item in value):
        return _substrings(variant, dimensions)
    if variant is None or not isinstance(value, list | tuple | str | bytes) or len(dimensions) != 1 \
            or dimensions[0][0] >= len(value):
        return _BAD.BadIndexRangeNoData  # a scalar, another number of dimensions, past the end
    first, last = dimensions[0]
    return ua.Variant(value[first:last + 1], variant.VariantType, is_array=isinstance(value, list | tuple))


def _substrings(variant: ua.Variant, dimensions: list[tuple[int, int]]) -> ua.Variant | int:
    """Part 4, 7.27: "Arrays of ByteString and String values are treated as two dimensional arrays
    where the final index specifies the substring range": the elements the first range selects,
    each cut to the second (an element too short for it is empty; none long enough: no data)."""
    (first, last), (start, end) = dimensions
    elements = variant.Value[first:last + 1]
    if not elements or all(start >= len(element) for element in elements):
        return _BAD.BadIndexRangeNoData
    return ua.Variant([element[start:end + 1] for element in elements], variant.VariantType, is_array=True)


def shaped(value: ua.DataValue, timestamps: ua.TimestampsToReturn, text: str | None) -> ua.DataValue:
    """A Value read as the request asks: its ``indexRange`` part and the timestamps it wants
    (a copy: asyncua's stored values are shared)."""
    if value.StatusCode is not None and value.StatusCode.is_bad():
        return value
    variant = value.Value
    if text:
        part = _range_of(variant, text)
        if isinstance(part, int):
            return ua.DataValue(StatusCode=_status(part))
        variant = part
    source = value.SourceTimestamp if timestamps in (ua.TimestampsToReturn.Source, ua.TimestampsToReturn.Both) else None
    server = None
    if timestamps in (ua.TimestampsToReturn.Server, ua.TimestampsToReturn.Both):
        server = value.ServerTimestamp or datetime.now(UTC)
    return ua.DataValue(variant, StatusCode=value.StatusCode, SourceTimestamp=source,
                        SourcePicoseconds=value.SourcePicoseconds if source is not None else None,
                        ServerTimestamp=server)


class NodeHistory(HistoryManager):
    """asyncua's HistoryRead (Part 4, 5.10.3) with Table 58's codes for what it answered Good with
    no data: ``Bad_NodeIdUnknown`` for a node the server does not have, and
    ``Bad_HistoryOperationUnsupported`` ("the requested history operation is not supported for the
    requested node") for a node that keeps no history: a Variable whose AccessLevel lacks
    HistoryRead (every point: the facade keeps no history) for a data history, a node whose
    EventNotifier lacks HistoryRead for an event history (Part 3, 5.4 and 5.6.2).  A history
    read asyncua does not implement (processed, at time) is that code too (asyncua:
    Bad_NotImplemented)."""

    async def _read_history(self, details: Any, rv: ua.HistoryReadValueId) -> ua.HistoryReadResult:
        aspace = self.iserver.aspace
        if rv.NodeId not in aspace:
            return ua.HistoryReadResult(StatusCode=_status(_BAD.BadNodeIdUnknown))
        events = isinstance(details, ua.ReadEventDetails)
        if not events and not isinstance(details, ua.ReadRawModifiedDetails):
            return ua.HistoryReadResult(StatusCode=_status(_BAD.BadHistoryOperationUnsupported))
        attribute = ua.AttributeIds.EventNotifier if events else ua.AttributeIds.AccessLevel
        bit = (ua.EventNotifier.HistoryRead if events else ua.AccessLevel.HistoryRead).mask
        if not (_value_of(aspace, rv.NodeId, attribute) or 0) & bit:
            return ua.HistoryReadResult(StatusCode=_status(_BAD.BadHistoryOperationUnsupported))
        return await super()._read_history(details, rv)


def _value_of(aspace: AddressSpace, node_id: ua.NodeId, attribute: ua.AttributeIds) -> Any:
    value = aspace.read_attribute_value(node_id, attribute)
    return value.Value.Value if value.StatusCode.is_good() and value.Value is not None else None


def derives(aspace: AddressSpace, data_type: Any, ancestor: ua.NodeId) -> bool:
    """Is ``data_type`` ``ancestor`` or one of its subtypes (inverse HasSubtype, Part 3, 7.10)?"""
    seen = set()
    while isinstance(data_type, ua.NodeId) and data_type not in seen and data_type in aspace:
        if data_type == ancestor:
            return True
        seen.add(data_type)
        data_type = next((ref.NodeId for ref in aspace[data_type].references
                          if not ref.IsForward and ref.ReferenceTypeId == _HAS_SUBTYPE), None)
    return False


def encoding_refusal(aspace: AddressSpace, item: ua.ReadValueId) -> int | None:
    """The status a dataEncoding asked for ``item`` (Read, CreateMonitoredItems) is refused with
    (Part 4, 7.34: Bad_DataEncodingInvalid unless it is the Value of a Structure;
    Bad_DataEncodingUnsupported for another encoding than ``Default Binary``, the one the server
    speaks), None when there is none to refuse.  The node and attribute exist."""
    encoding = item.DataEncoding
    if encoding is None or not encoding.Name:
        return None
    data_type = _value_of(aspace, item.NodeId, ua.AttributeIds.DataType)
    if item.AttributeId != ua.AttributeIds.Value or not derives(aspace, data_type, _STRUCTURE):
        return _BAD.BadDataEncodingInvalid
    if encoding != _DEFAULT_BINARY:
        return _BAD.BadDataEncodingUnsupported
    return None


class ContinuationPoints:
    """One connection's Browse continuation points (Part 4, 7.9 (v1.05; 7.6 in v1.04)): the
    references a Browse or BrowseNext had no room for (``requestedMaxReferencesPerNode``), each
    under an opaque 16-byte value until BrowseNext fetches or releases it.  At most :data:`MOST`
    at a time: a new one frees the oldest ("a Server shall automatically free ContinuationPoints
    from prior requests ... if they are needed to process a new request"), which is then
    Bad_ContinuationPointInvalid, as one released or never given is."""

    MOST = 16  # the ServerCapabilities' MaxBrowseContinuationPoints

    def __init__(self) -> None:
        self._kept: dict[bytes, tuple[list[ua.ReferenceDescription], int]] = {}

    def page(self, result: ua.BrowseResult, limit: int) -> None:
        """Cut ``result`` to ``limit`` references (0: no limit), keeping the rest under a new point."""
        if not limit or len(result.References) <= limit:
            return
        rest, result.References = result.References[limit:], result.References[:limit]
        while len(self._kept) >= self.MOST:
            del self._kept[next(iter(self._kept))]  # the oldest
        point = os.urandom(16)
        self._kept[point] = (rest, limit)
        result.ContinuationPoint = point

    def browse_next(self, params: ua.BrowseNextParameters) -> list[ua.BrowseResult]:
        """The BrowseNext results (Part 4, 5.8.3): the next references of each point, or, when the
        points are released, a result without references for each (Good, or
        Bad_ContinuationPointInvalid for one it did not have).  Part 4 says the results "are
        empty" then; node-opcua's client and the OPC Foundation's .NET client both want one result
        a point (node-opcua fails an assertion on an empty list), so each result is empty."""
        results = []
        for point in params.ContinuationPoints:
            kept = self._kept.pop(point, None)
            result = ua.BrowseResult()
            if kept is None:
                result.StatusCode = _status(_BAD.BadContinuationPointInvalid)
            elif not params.ReleaseContinuationPoints:
                result.References = kept[0]
                self.page(result, kept[1])
            results.append(result)
        return results


#: the continuation points of the connection whose request is served (set by
#: :class:`devsim.facades.opcua_decoding.RequestDecoding`; None: the server's own browsing, unpaged)
CONTINUATION: ContextVar[ContinuationPoints | None] = ContextVar("continuation", default=None)


class NodeView(ViewService):
    """asyncua's view service, with Bad_NodeIdUnknown for a node it does not have (Browse's node,
    TranslateBrowsePathsToNodeIds' startingNode), and a client's ``requestedMaxReferencesPerNode``
    honoured with continuation points (:class:`ContinuationPoints`; asyncua returned every
    reference whatever the client asked for).  Part 4's codes where asyncua answered otherwise:
    Bad_ViewIdUnknown for a Browse of a view that is not a View node of the server (5.8.2.3 Table
    35, the whole request; the server has none: asyncua browsed the whole address space),
    Bad_ReferenceTypeIdInvalid for a referenceTypeId that is not a ReferenceType (5.8.2.4 Table
    36; asyncua: Good, no references); for a browse path, Bad_NothingToDo for an empty
    relativePath (5.8.4.4 Table 42; asyncua failed the whole request with Bad_InternalError) and
    Bad_BrowseNameInvalid for an element without a targetName (Table 42 and 5.8.4.2: "The Server
    shall return Bad_BrowseNameInvalid if the targetName is missing"; asyncua: Bad_NoMatch)."""

    def browse(self, params: ua.BrowseParameters) -> list[ua.BrowseResult]:
        view = params.View.ViewId if params.View is not None else None
        if view is not None and not view.is_null() and not self._is(view, ua.NodeClass.View):
            raise ua.UaStatusCodeError(_BAD.BadViewIdUnknown)
        results = super().browse(params)
        points = CONTINUATION.get()
        if points is not None:
            for result in results:
                points.page(result, params.RequestedMaxReferencesPerNode)
        return results

    def _browse(self, desc: ua.BrowseDescription) -> ua.BrowseResult:
        if desc.NodeId not in self._aspace:
            result = ua.BrowseResult()
            result.StatusCode = _status(_BAD.BadNodeIdUnknown)
            return result
        reference = desc.ReferenceTypeId
        if reference is not None and not reference.is_null() and not self._is(reference, ua.NodeClass.ReferenceType):
            result = ua.BrowseResult()
            result.StatusCode = _status(_BAD.BadReferenceTypeIdInvalid)
            return result
        return super()._browse(desc)

    def _is(self, node_id: ua.NodeId, node_class: ua.NodeClass) -> bool:
        """Is ``node_id`` a node of the server of that NodeClass?"""
        return node_id in self._aspace and _value_of(self._aspace, node_id, ua.AttributeIds.NodeClass) == node_class

    def _translate_browsepath_to_nodeid(self, path: ua.BrowsePath) -> ua.BrowsePathResult:
        elements = path.RelativePath.Elements if path.RelativePath is not None else []
        refused = (_BAD.BadNothingToDo if not elements
                   else _BAD.BadBrowseNameInvalid if any(not (e.TargetName and e.TargetName.Name) for e in elements)
                   else None)
        if refused is not None:
            result = ua.BrowsePathResult()
            result.StatusCode = _status(refused)
            return result
        result = super()._translate_browsepath_to_nodeid(path)
        if result.StatusCode.value == _BAD.BadNodeIdInvalid and path.StartingNode not in self._aspace:
            result.StatusCode = _status(_BAD.BadNodeIdUnknown)  # (asyncua's code for it: Bad_NodeIdInvalid)
        return result


def call_result(status: int, arguments: list[int] | None = None) -> ua.CallMethodResult:
    """A Call result: ``status`` and, for Bad_InvalidArgument, a status per input argument."""
    result = ua.CallMethodResult()
    result.StatusCode = _status(status)
    result.InputArgumentResults = [_status(code) for code in arguments or []]
    return result


class DeviceMethods(MethodService):
    """asyncua's method service with Part 4's checks of the object, the method and the input
    arguments (their number and built-in types, from the method's InputArguments property)
    before the method runs."""

    async def _call(self, method: ua.CallMethodRequest) -> ua.CallMethodResult:
        refused = self._refusal(method)
        if refused is not None:
            return refused
        return await super()._call(method)

    def _refusal(self, method: ua.CallMethodRequest) -> ua.CallMethodResult | None:
        aspace = self._aspace
        if method.ObjectId not in aspace:
            return call_result(_BAD.BadNodeIdUnknown)
        if aspace[method.ObjectId].attributes[ua.AttributeIds.NodeClass].value.Value.Value not in _OBJECTS:
            return call_result(_BAD.BadNodeIdInvalid)
        if not self._component(method.ObjectId, method.MethodId):
            return call_result(_BAD.BadMethodInvalid)
        declared = self._input_arguments(method.MethodId)
        given = method.InputArguments or []
        if len(given) < len(declared):
            return call_result(_BAD.BadArgumentsMissing)
        if len(given) > len(declared):
            return call_result(_BAD.BadTooManyArguments)
        results = [_BAD.Good if _fits(argument, variant) else _BAD.BadTypeMismatch
                   for argument, variant in zip(declared, given, strict=True)]
        if any(code != _BAD.Good for code in results):
            return call_result(_BAD.BadInvalidArgument, results)
        return None

    def _component(self, object_id: ua.NodeId, method_id: ua.NodeId) -> bool:
        """Is ``method_id`` a method the object has (HasComponent, from it or its type)?"""
        if method_id not in self._aspace:
            return False
        method = self._aspace[method_id]
        if method.attributes[ua.AttributeIds.NodeClass].value.Value.Value != ua.NodeClass.Method:
            return False
        holders = [object_id]
        for ref in self._aspace[object_id].references:
            if ref.IsForward and ref.ReferenceTypeId == ua.NodeId(ua.ObjectIds.HasTypeDefinition):
                holders.append(ref.NodeId)
        return any(ref.IsForward and ref.NodeId == method_id and ref.ReferenceTypeId == ua.NodeId(ua.ObjectIds.HasComponent)
                   for holder in holders if holder in self._aspace for ref in self._aspace[holder].references)

    def _input_arguments(self, method_id: ua.NodeId) -> list[ua.Argument]:
        for ref in self._aspace[method_id].references:
            if ref.IsForward and ref.BrowseName.Name == "InputArguments" and ref.NodeId in self._aspace:
                value = self._aspace.read_attribute_value(ref.NodeId, ua.AttributeIds.Value).Value
                return list(value.Value or []) if value is not None else []
        return []


def _fits(argument: ua.Argument, variant: ua.Variant) -> bool:
    """A scalar of the argument's built-in type (other data types: not checked here)."""
    data_type = argument.DataType
    if data_type.NamespaceIndex != 0 or data_type.Identifier not in _BUILT_IN:
        return True
    return variant.VariantType.value == data_type.Identifier and not variant.is_array
