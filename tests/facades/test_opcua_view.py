"""The OPC UA facade's View service set against OPC UA Part 4 (5.8), through asyncua's client and
node-opcua's: TranslateBrowsePathsToNodeIds (5.8.4) finds a point's variable by its browse name,
dots and all, and answers a startingNode the server does not have with Bad_NodeIdUnknown (asyncua:
Bad_NodeIdInvalid, which Part 4 keeps for a NodeId of invalid syntax)."""

from __future__ import annotations

from collections.abc import Iterator

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
]


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
