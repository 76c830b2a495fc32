"""CANopen nodes from a plant file (issue 13): ``canopen: {node, network}`` per device; the devices
with the same network share one CAN bus behind one socketcand server, where canopen (python-can's
socketcand client) reads each node's identity and a point."""

from __future__ import annotations

from pathlib import Path

import pytest

from devsim.core.typed import Invalid
from devsim.scenario.plant import plant_running
from devsim.scenario.schema import PlantSpec
from tests.support.can import network as can_network

ROOT = Path(__file__).resolve().parents[2]


def _plant(**network: str) -> PlantSpec:
    where = {"network": network["network"]} if network else {}
    return PlantSpec.parse({"devices": [
        {"name": "x", "kind": "sers", "canopen": {"node": 5, **where}},
        {"name": "y", "kind": "gms96", "canopen": {"node": 6, **where}},
        {"name": "z", "kind": "sers"},
    ]})


def test_two_devices_of_a_plant_on_one_can_network() -> None:
    with plant_running(_plant(network="127.0.0.1:0"), virtual=True) as plant:
        rows = [row for row in plant.describe() if ".canopen:" in row]
        assert len(rows) == 2 and rows[0].startswith("x.canopen: socketcand 127.0.0.1:")
        where = rows[0].split()[2]
        assert rows[1] == f"y.canopen: socketcand {where} can0 node 6"
        host, _, port = where.rpartition(":")
        network = can_network()
        network.connect(interface="socketcand", host=host, port=int(port), channel="can0")
        try:
            x = network.add_node(5, str(ROOT / "docs" / "eds" / "sers.eds"))
            y = network.add_node(6, str(ROOT / "docs" / "eds" / "gms96.eds"))
            assert (x.sdo[0x1008].raw, y.sdo[0x1008].raw) == ("devsim sers", "devsim gms96")
            x.sdo["quantity.supply_voltage"].raw = 50.0
            assert plant.runtime.read("x", "quantity.supply_voltage") == 50.0
        finally:
            network.disconnect()


def test_node_ids_on_one_network_must_differ() -> None:
    """Refused with the plant (devsim check names it), before anything is served."""
    with pytest.raises(Invalid, match="devices.2.canopen.node: CANopen node 5 on 127.0.0.1:0 is taken by"):
        PlantSpec.parse({"devices": [
            {"name": "x", "kind": "sers", "canopen": {"node": 5, "network": "127.0.0.1:0"}},
            {"name": "y", "kind": "sers", "canopen": {"node": 5, "network": "127.0.0.1:0"}},
        ]})


@pytest.mark.parametrize("bad", [{"node": 0}, {"node": 128}, {"node": 5, "network": "somewhere"}])
def test_a_bad_canopen_entry_is_refused(bad: dict) -> None:
    with pytest.raises(Invalid):
        PlantSpec.parse({"devices": [{"name": "x", "kind": "sers", "canopen": bad}]})
