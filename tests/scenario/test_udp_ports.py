"""UDP in plant and scenario files: the ``udp`` transport spec, a port's declared default (on an
ephemeral port number, so plants run side by side), the scripted host's UDP port, pcap traces."""

from __future__ import annotations

import socket
from pathlib import Path

import pytest

from devsim.scenario.plant import plant_running
from devsim.scenario.report import format_report
from devsim.scenario.runner import run_scenario
from devsim.scenario.schema import PlantSpec, TransportSpec, scenario_from_dict
from tests.support.etherbus import read_request
from tests.transports.test_pcap import read_pcap

ETHERBUS = "etherbus=tests.support.etherbus:EtherBusDevice"
REQUEST = bytes.fromhex("00000010 01 00 0001 00 01 06 00 00D5 9409")
REPLY = bytes.fromhex("0000000F 01 00 0001 01 000003E8 7B16")


@pytest.fixture(autouse=True)
def _kinds(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("DEVSIM_EXTRA_KINDS", ETHERBUS)


def plant(**device: object) -> PlantSpec:
    return PlantSpec.parse({"devices": [{"name": "pcd", "kind": "etherbus", **device}]})


def ask(url: str, request: bytes = REQUEST) -> bytes:
    scheme, _, rest = url.partition("://")
    host, _, number = rest.rpartition(":")
    assert scheme == "udp"
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.settimeout(5)
        sock.sendto(request, (host, int(number)))
        return sock.recv(100)


def test_the_udp_spec() -> None:
    spec = TransportSpec.parse({"udp": {"port": 5050}})
    assert spec.kind == "udp" and spec.udp is not None and (spec.udp.host, spec.udp.port) == ("127.0.0.1", 5050)
    with pytest.raises(ValueError, match="give one transport, not tcp and udp"):
        TransportSpec.parse({"tcp": {}, "udp": {}})


def test_a_declared_default_gives_its_scheme_on_an_ephemeral_port() -> None:
    device = plant().devices[0]
    assert device.transport_of("serial").kind == "pty"
    ether = device.transport_of("ether")
    assert ether.kind == "udp" and ether.udp is not None and ether.udp.port == 0
    given = plant(ports={"ether": {"udp": {"port": 5050}}}).devices[0].transport_of("ether")
    assert given.udp is not None and given.udp.port == 5050
    assert plant(ports={"ether": {"pty": {}}}).devices[0].transport_of("ether").kind == "pty"


def test_two_plants_side_by_side_answer_on_their_own_udp_ports() -> None:
    with plant_running(plant(), virtual=True) as one, plant_running(plant(), virtual=True) as two:
        urls = [p.port("pcd.ether") for p in (one, two)]
        assert all(url.startswith("udp://127.0.0.1:") for url in urls) and urls[0] != urls[1]
        assert one.kinds["pcd.ether"] == "udp" and one.kinds["pcd.serial"] == "pty"
        assert f"pcd.ether: udp {urls[0]}" in one.describe()
        assert one.runtime.ports["pcd.ether"] == urls[0]  # the address map, as for every port
        assert ask(urls[0]) == REPLY
        assert ask(urls[1], read_request(2, 1, 10))[9:13] == (50).to_bytes(4, "big")
        assert one.runtime.read("pcd", "answered") == 1 and two.runtime.read("pcd", "answered") == 1


def test_plant_traces_as_pcap(tmp_path: Path) -> None:
    with plant_running(plant(), virtual=True, trace_dir=tmp_path, trace_format="pcap") as running:
        assert ask(running.port("pcd.ether")) == REPLY
    assert sorted(p.name for p in tmp_path.iterdir()) == ["pcd.ether.pcap", "pcd.serial.pcap"]
    assert [p[3] for p in read_pcap(tmp_path / "pcd.ether.pcap")] == [REQUEST, REPLY]


def test_a_scenario_talks_to_a_udp_port() -> None:
    data = {
        "devices": [{"name": "pcd", "kind": "etherbus"}],
        "steps": [
            {"send": {"port": "pcd.ether", "data": REQUEST.decode("latin-1")}},
            {"expect": {"port": "pcd.ether", "bytes": REPLY.decode("latin-1")}},
            {"send": {"port": "pcd.ether", "data": "garbage"}},
            {"send": {"port": "pcd.ether", "data": read_request(9, 1, 213).decode("latin-1")}},
            {"expect": {"port": "pcd.ether", "regex": "\\x00\\x09\\x01\\x00\\x00\\x03\\xe8"}},
            {"expect_state": {"device": "pcd", "name": "ignored", "equals": 1}},
        ],
    }
    result = run_scenario(scenario_from_dict(data, "udp"))
    assert result.passed, format_report(result)
    assert result.ports["pcd.ether"].startswith("udp://127.0.0.1:")
