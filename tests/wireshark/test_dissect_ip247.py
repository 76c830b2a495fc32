"""An IP247 PG-port session (AS511) through a real pty of ``devsim run ip247 --trace x.pcap``,
decoded by tshark with devsim's Lua dissectors: the job telegrams' function, page, Betriebsart,
command and parameters as sent, DLE doubling, the response header's error number, a refused
function (DLE NAK)."""

from __future__ import annotations

from pathlib import Path

import serial

from devsim.devices.ip247.client import PgClient
from devsim.devices.ip247.pg_profile import OBSERVE, OPERATE, READ_REC
from devsim.devices.ip247.tables import MODULE_ERRORS
from tests.support.programs import needs_program
from tests.wireshark.captures import Session, tshark_fields

SYSTEM_PARAMETERS = 0x18  # an S5 service this port refuses (spec §3.6.7 f)
NO_MACHINE_DATA = 14  # "Keine oder falsche Maschinendaten" (manual §7.2)


def values(rows: list[list[str]], index: int) -> list[str]:
    return [value for row in rows if row[index] for value in row[index].split("|")]


def test_an_ip247_pg_session_decodes_with_jobs_and_error_numbers(tmp_path: Path) -> None:
    needs_program("tshark")
    with Session(tmp_path, "ip247") as sim, serial.Serial(sim.ports["ip247.pg"], 9600, parity="E", timeout=5) as port:
        client = PgClient(port)
        assert client.transaction(READ_REC, bytes((4, 70, 0, 0)))[8:14] == b"IP247 "  # type: ignore[index]
        # BA6 Start, W 100, DD 4112 = 00 00 10 10: two DLE bytes, doubled on the line
        answer = client.transaction(OPERATE, bytes.fromhex("01 06 01 00 00 64 00 00 10 10"))
        assert answer is not None and answer[4] == NO_MACHINE_DATA  # no machine data yet: refused job
        client.transaction(OBSERVE, b"\x01")
        port.write(b"\x02")
        assert port.read(2) == b"\x10\x06"
        port.write(bytes((SYSTEM_PARAMETERS,)))
        assert port.read(2) == b"\x10\x15"
    rows = tshark_fields(sim.capture, ["devsim.dir", "as511.function", "as511.page", "as511.ba", "as511.cmd",
                                       "as511.w", "as511.dd", "as511.dle_doubled", "as511.error", "as511.control"])
    host = [row for row in rows if row[0] == "0"]
    device = [row for row in rows if row[0] == "1"]
    assert values(host, 1) == ["0x64", "0x61", "0x62", "0x18"]
    assert values(host, 2) == ["4", "1", "1"]
    assert values(host, 3) == ["70", "6"]
    assert values(host, 4) == ["1"]  # Start
    assert (values(host, 5), values(host, 6), values(host, 7)) == (["100"], ["4112"], ["2"])
    assert values(device, 8) == ["0", str(NO_MACHINE_DATA), str(NO_MACHINE_DATA)]
    assert values(device, 9)[-1] == "DLE NAK"
    shown = tshark_fields(sim.capture, ["as511.error.text", "as511.error.pg"], display_filter="as511.error == 14")
    assert values(shown, 0) == [MODULE_ERRORS[NO_MACHINE_DATA][0]] * 2
    assert values(shown, 1) == ["0x8e"] * 2  # "8E: Keine oder falsche Maschinendaten" on COM247's screen
