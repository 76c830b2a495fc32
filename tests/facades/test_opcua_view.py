"""The OPC UA facade's View service set against OPC UA Part 4 (5.8), through asyncua's client and
node-opcua's: TranslateBrowsePathsToNodeIds (5.8.4) finds a point's variable by its browse name,
dots and all, and answers a startingNode the server does not have with Bad_NodeIdUnknown (asyncua:
Bad_NodeIdInvalid, which Part 4 keeps for a NodeId of invalid syntax), a path of no elements with
Bad_NothingToDo (asyncua failed the whole request with Bad_InternalError) and one with an element
without a targetName with Bad_BrowseNameInvalid (5.8.4.4 Table 42; asyncua: Bad_NoMatch).  A Browse
of a referenceTypeId that is not a ReferenceType is Bad_ReferenceTypeIdInvalid (5.8.2.4 Table 36;
asyncua: Good, no references), one of a view the server does not have Bad_ViewIdUnknown (5.8.2.3
Table 35, the whole request; asyncua browsed the whole address space).

Browse (5.8.2) returns no more references a node than requestedMaxReferencesPerNode, the rest
behind a continuation point that BrowseNext (5.8.3) continues (page after page, the same
references as one Browse without a limit) or releases (a result without references; the point is
then Bad_ContinuationPointInvalid, as a made-up one is).  A connection keeps at most the
ServerCapabilities' MaxBrowseContinuationPoints: a new one frees the oldest.  asyncua sent every
reference whatever the limit, and refused BrowseNext, as any service it does not serve, with
Bad_UserAccessDenied instead of Bad_ServiceUnsupported."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest
from asyncua import Client, ua

from devsim.facades.opcua import OpcuaFacade, start_opcua
from devsim.facades.opcua_space import NAMESPACE
from devsim.runtime import Runtime
from tests.facades.opcua_clients import node_client

#: (starting node, browse names along the path) -> (status, the target's string node id or None)
PATHS = [
    ("sers", ["axis.position"], "Good", "sers.axis.position"),
    ("sers", ["Kind"], "Good", "sers#Kind"),
    ("sers", ["nope"], "BadNoMatch", None),
    ("nope", ["axis.position"], "BadNodeIdUnknown", None),
    ("sers", [], "BadNothingToDo", None),  # 5.8.4.4 Table 42: "the relativePath contained an empty list"
    ("sers", [""], "BadBrowseNameInvalid", None),  # "a TargetName was missing in a RelativePath"
    ("sers", ["", "axis.position"], "BadBrowseNameInvalid", None),  # (7.26: shall be given but in the last)
]
#: (node browsed, referenceTypeId) -> the status of its result, all in one Browse (5.8.2.4 Table 36)
BROWSES = [
    ("sers", "i=33", "Good"),  # HierarchicalReferences
    ("sers", "i=85", "BadReferenceTypeIdInvalid"),  # the Objects folder: not a ReferenceType
    ("sers", "i=999999", "BadReferenceTypeIdInvalid"),  # no such node
    ("nope", "i=33", "BadNodeIdUnknown"),
]
#: ViewIds a Browse may not name (5.8.2.3 Table 35: Bad_ViewIdUnknown, the whole request): the
#: server has no View but the whole address space (a null ViewId)
VIEWS = ["i=85", "ns=1;s=nope"]


@pytest.fixture(scope="module")
def served() -> Iterator[tuple[Runtime, OpcuaFacade]]:
    runtime = Runtime(virtual=True).start()
    try:
        facade = runtime.run(start_opcua(runtime, [runtime.add_device("sers", "sers")], "127.0.0.1:0"), timeout=60)
        yield runtime, facade
    finally:
        runtime.stop()


async def test_asyncua_translate_browse_paths(served: tuple[Runtime, OpcuaFacade]) -> None:
    _, facade = served
    async with Client(facade.url) as client:
        ns = await client.get_namespace_index(NAMESPACE)
        paths = [ua.BrowsePath(StartingNode=ua.NodeId(start, ns), RelativePath=ua.RelativePath(Elements=[
            ua.RelativePathElement(ReferenceTypeId=ua.NodeId(ua.ObjectIds.HierarchicalReferences), IsInverse=False,
                                   IncludeSubtypes=True, TargetName=ua.QualifiedName(name, ns)) for name in names]))
            for start, names, *_ in PATHS]
        results = await client.uaclient.translate_browsepaths_to_nodeids(paths)
    got = [(result.StatusCode.name, [target.TargetId for target in result.Targets]) for result in results]
    assert got == [(status, [ua.NodeId(target, ns)] if target else []) for *_, status, target in PATHS]


def test_node_opcua_translate_browse_paths(served: tuple[Runtime, OpcuaFacade]) -> None:
    _, facade = served
    results = node_client(facade.url, [{"op": "translate", "node": start, "path": names} for start, names, *_ in PATHS])
    got = [(result["status"], [target.split(";s=", 1)[1] for target in result["targets"]]) for result in results]
    assert got == [(status, [target] if target else []) for *_, status, target in PATHS]


def _descriptions(ns: int) -> list[ua.BrowseDescription]:
    return [ua.BrowseDescription(NodeId=ua.NodeId(node, ns), BrowseDirection=ua.BrowseDirection.Forward,
                                 ReferenceTypeId=ua.NodeId.from_string(reference), IncludeSubtypes=True,
                                 ResultMask=ua.BrowseResultMask.All) for node, reference, _ in BROWSES]


async def test_asyncua_a_browse_of_a_reference_type_or_view_the_server_does_not_have(
        served: tuple[Runtime, OpcuaFacade]) -> None:
    """asyncua answered Good with no references for the reference types, and browsed the whole
    address space for any view."""
    _, facade = served
    async with Client(facade.url) as client:
        ns = await client.get_namespace_index(NAMESPACE)
        results = await client.uaclient.browse(ua.BrowseParameters(NodesToBrowse=_descriptions(ns)))
        assert [result.StatusCode.name for result in results] == [status for *_, status in BROWSES]
        assert len(results[0].References) > 40
        for view in VIEWS:
            with pytest.raises(ua.uaerrors.BadViewIdUnknown):
                await client.uaclient.browse(ua.BrowseParameters(
                    View=ua.ViewDescription(ViewId=ua.NodeId.from_string(view)), NodesToBrowse=_descriptions(ns)[:1]))
        [whole] = await client.uaclient.browse(ua.BrowseParameters(View=ua.ViewDescription(),
                                                                   NodesToBrowse=_descriptions(ns)[:1]))
        assert whole.References == results[0].References


def test_node_opcua_a_browse_of_a_reference_type_or_view_the_server_does_not_have(
        served: tuple[Runtime, OpcuaFacade]) -> None:
    _, facade = served
    items = [{"node": node, "referenceTypeId": reference} for node, reference, _ in BROWSES]
    plan = [{"op": "browses", "items": items}] + [{"op": "browses", "items": items[:1], "view": view} for view in VIEWS]
    browsed, *viewed = node_client(facade.url, plan)
    assert browsed["statuses"] == [status for *_, status in BROWSES]
    assert viewed == [{"fault": "BadViewIdUnknown"}] * len(VIEWS)


def _browse(ns: int, limit: int) -> ua.BrowseParameters:
    return ua.BrowseParameters(RequestedMaxReferencesPerNode=limit, NodesToBrowse=[ua.BrowseDescription(
        NodeId=ua.NodeId("sers", ns), BrowseDirection=ua.BrowseDirection.Forward,
        ReferenceTypeId=ua.NodeId(ua.ObjectIds.HierarchicalReferences), IncludeSubtypes=True,
        ResultMask=ua.BrowseResultMask.All)])


async def _next(client: Client, points: list[bytes], release: bool = False) -> list[ua.BrowseResult]:
    return await client.uaclient.browse_next(ua.BrowseNextParameters(ReleaseContinuationPoints=release,
                                                                      ContinuationPoints=points))


async def test_asyncua_browse_pages_with_continuation_points(served: tuple[Runtime, OpcuaFacade]) -> None:
    _, facade = served
    async with Client(facade.url) as client:
        ns = await client.get_namespace_index(NAMESPACE)
        [whole] = await client.uaclient.browse(_browse(ns, 0))
        assert len(whole.References) > 40 and not whole.ContinuationPoint
        [result] = await client.uaclient.browse(_browse(ns, 7))
        pages, names = [len(result.References)], [ref.BrowseName.Name for ref in result.References]
        while result.ContinuationPoint:
            [result] = await _next(client, [result.ContinuationPoint])
            assert result.StatusCode.is_good()
            pages.append(len(result.References))
            names += [ref.BrowseName.Name for ref in result.References]
        assert names == [ref.BrowseName.Name for ref in whole.References]
        assert set(pages[:-1]) == {7} and 0 < pages[-1] <= 7
        [result] = await client.uaclient.browse(_browse(ns, 7))
        [released] = await _next(client, [result.ContinuationPoint], release=True)  # released: no references
        assert (released.StatusCode.name, released.References, released.ContinuationPoint) == ("Good", [], None)
        [again, made_up] = await _next(client, [result.ContinuationPoint, b"\x00\xff"])
        assert again.StatusCode.name == made_up.StatusCode.name == "BadContinuationPointInvalid"
        most = await client.get_node(ua.ObjectIds.Server_ServerCapabilities_MaxBrowseContinuationPoints).read_value()
        points = [(await client.uaclient.browse(_browse(ns, 1)))[0].ContinuationPoint for _ in range(most + 1)]
        [oldest, newest] = await _next(client, [points[0], points[-1]])  # one more than it keeps: the oldest went
        assert (oldest.StatusCode.name, newest.StatusCode.name) == ("BadContinuationPointInvalid", "Good")
        with pytest.raises(ua.uaerrors.BadNothingToDo):
            await _next(client, [])
        with pytest.raises(ua.uaerrors.BadServiceUnsupported):  # a service asyncua's server does not serve
            await client.uaclient.protocol.send_request(ua.QueryFirstRequest())
        assert await client.get_node(ua.NodeId("sers.quantity.supply_voltage", ns)).read_value() == 68.0


def test_node_opcua_browse_pages_with_continuation_points(served: tuple[Runtime, OpcuaFacade]) -> None:
    _, facade = served
    plan: list[dict[str, Any]] = [{"op": "paged", "node": "sers", "max": 0}, {"op": "paged", "node": "sers", "max": 7},
                                  {"op": "paged", "node": "sers", "max": 7, "release": True},
                                  {"op": "paged", "points": ["00ff"]}]
    whole, paged, released, made_up = node_client(facade.url, plan)
    assert len(whole["pages"]) == 1 and whole["pages"][0] > 40
    assert paged["names"] == whole["names"] and paged["status"] == "Good"
    assert set(paged["pages"][:-1]) == {7} and 0 < paged["pages"][-1] <= 7
    assert released == {"pages": [7], "released": 1, "again": "BadContinuationPointInvalid"}
    assert made_up == {"statuses": ["BadContinuationPointInvalid"]}
