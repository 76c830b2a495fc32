"""`devsim run KIND --opcua [[HOST:]PORT]` and a plant file's `opcua:` section (issue 14): the
devices on one OPC UA server beside their own ports, read with asyncua's client."""

from __future__ import annotations

import pytest
from asyncua import Client, ua
from click.testing import CliRunner

from devsim.cli import cli
from devsim.core.typed import Invalid
from devsim.facades.opcua_space import NAMESPACE, endpoint_url
from devsim.scenario.plant import plant_running
from devsim.scenario.schema import PlantSpec
from tests.test_cli import Sim


async def _read(url: str, node_id: str) -> object:
    async with Client(url) as client:
        ns = await client.get_namespace_index(NAMESPACE)
        return await client.get_node(ua.NodeId(node_id, ns)).read_value()


async def test_run_serves_opcua_beside_the_pty() -> None:
    sim = Sim("sers", "--pty", "--virtual", "--opcua", "127.0.0.1:0")
    try:
        seen = sim.read_until("opcua:")
        assert seen["sers"].startswith("pty /dev/")
        url = seen["opcua"]
        assert url.startswith("opc.tcp://127.0.0.1:") and url.endswith("/devsim/") and ":0/" not in url
        assert await _read(url, "sers.quantity.supply_voltage") == 68.0
    finally:
        sim.stop()


async def test_what_asyncua_logs_about_bad_requests_is_rate_limited() -> None:
    """A client that sends bad requests over and over (here a negative maxAge) does not fill the
    simulator's stderr: one line a kind of message every ten seconds, headed devsim: opcua: (it
    was a line per request, and a 23-line traceback per request asyncua cannot decode)."""
    sim = Sim("sers", "--pty", "--virtual", "--opcua", "127.0.0.1:0")
    try:
        url = sim.read_until("opcua:")["opcua"]
        async with Client(url) as client:
            ns = await client.get_namespace_index(NAMESPACE)
            for _ in range(30):
                with pytest.raises(ua.uaerrors.BadMaxAgeInvalid):
                    await client.uaclient.read(ua.ReadParameters(NodesToRead=[ua.ReadValueId(
                        NodeId=ua.NodeId("sers.quantity.supply_voltage", ns), AttributeId=ua.AttributeIds.Value)],
                        MaxAge=-1))
    finally:
        _status, err = sim.stop()
    about = [line for line in err.splitlines() if "max age" in line.lower()]
    assert len(about) == 1 and about[0].startswith("devsim: opcua: "), err


@pytest.mark.parametrize(("spec", "url"), [
    ("", "opc.tcp://127.0.0.1:4840/devsim/"),
    ("4841", "opc.tcp://127.0.0.1:4841/devsim/"),
    ("0.0.0.0:4842", "opc.tcp://0.0.0.0:4842/devsim/"),
    ("opc.tcp://localhost:4843/plant/", "opc.tcp://localhost:4843/plant/"),
])
def test_the_endpoint_is_loopback_unless_a_host_is_named(spec: str, url: str) -> None:
    assert endpoint_url(spec) == url


def test_a_bad_opcua_spec_is_one_line() -> None:
    result = CliRunner().invoke(cli, ["run", "sers", "--opcua", "host:port"])
    assert result.exit_code == 2 and "--opcua: expected [HOST:]PORT, not 'host:port'" in result.output


async def test_a_plant_serves_its_devices_on_one_opcua_server() -> None:
    spec = PlantSpec.parse({
        "name": "cell",
        "devices": [{"name": "x", "kind": "sers", "state": {"quantity.heatsink_temperature": 47.5}},
                    {"name": "y", "kind": "sers"}],
        "opcua": {"port": 0, "period": "50ms"},
    })
    assert spec.opcua is not None and spec.opcua.period == 0.05
    with plant_running(spec, virtual=True) as plant:
        url = plant.port("opcua")
        assert f"opcua: {url}" in plant.describe()  # as devsim run prints it (docs/facades/opcua.md)
        assert await _read(url, "x.quantity.heatsink_temperature") == 47.5
        assert await _read(url, "y.quantity.heatsink_temperature") == plant.runtime.read(
            "y", "quantity.heatsink_temperature")


def test_no_device_may_take_the_opcua_servers_port_name() -> None:
    with pytest.raises(Invalid, match="named 'opcua'"):
        PlantSpec.parse({"devices": [{"name": "opcua", "kind": "sers"}], "opcua": {}})
