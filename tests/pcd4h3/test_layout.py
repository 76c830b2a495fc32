"""The H3 library's media layout (spec pcd4h3.md §4.1–§4.3) against the addresses of the §9.4
vectors (Example configuration BAR = BAF = 200; default BAR = BAF = 2000)."""

from __future__ import annotations

from devsim.devices.pcd4h3.layout import FLAGS_PER_AXIS, REGISTERS_PER_AXIS, Layout
from devsim.devices.pcd4h3.tables import FLAG_FIELD as FLAGS
from devsim.devices.pcd4h3.tables import REGISTERS
from devsim.devices.pcd4h3.units import ffp_decode


def test_tables_fill_the_blocks() -> None:
    assert [r.key for r in REGISTERS] == list(range(REGISTERS_PER_AXIS))
    assert [f.key for f in FLAGS] == list(range(FLAGS_PER_AXIS))
    commands = [f for f in FLAGS if f.extra["kind"] == "command"]
    assert len(commands) == 29 and commands[0].name == "FLdDR" and commands[-1].name == "FBackw"
    assert ffp_decode(next(r for r in REGISTERS if r.name == "MCFac").default) == 100.0


def test_addresses_of_the_vectors() -> None:
    example = Layout(bar=200, baf=200, axes=1)
    assert example.register(1, "DestP") == 207  # V1
    assert example.flag(1, "FLdDA") == 207  # V2
    assert example.flag(1, "FStart") == 228  # V3
    assert [example.flag(1, s) for s in ("OnDest", "BrkPos")] == [200, 204]  # V4
    assert example.register(1, "RActP") == 213 and example.register(1, "MCW") == 212  # V6, V8
    assert example.register(1, "MCFac") == 205 and example.register(1, "RSigB") == 219  # V10, V12
    default = Layout()
    assert default.register(1, "DestP") == 2007 and default.flag(1, "FLdDA") == 2007  # V20, V21
    assert default.register(2, "DestP") == 2027 and default.flag(2, "FStart") == 2063
    assert default.locate_register(2027)[0] == 2 and default.locate_register(2027)[1].name == "DestP"  # type: ignore[index]
    assert default.locate_flag(2063) == (2, "FStart") and default.locate_flag(2070) is None


def test_a_flag_map_moves_reconstructed_offsets() -> None:
    moved = Layout(bar=200, baf=200, axes=1, flag_map={"FStart": 30, "FMotOff": 28})
    assert moved.flag(1, "FStart") == 230 and moved.locate_flag(228) == (1, "FMotOff")
