"""POSELESTA sessions through real ptys of ``devsim run poselesta --trace x.pcap`` (one capture
per port), decoded by tshark with devsim's Lua dissectors: a V7 DNC read-in and output (program
text, %, blocks with their words, EOB; ISO parity on the way in, ASCII out) and V8 key codes
(manual §2.6.3, §2.6.4)."""

from __future__ import annotations

import json
import time
from pathlib import Path

import serial

from tests.support.programs import needs_program
from tests.wireshark.captures import Session, tshark_fields, write_pcap

#: Spec vector R1 (§6.7): NUL leader, % and two blocks in ISO (parity in bit 7), M30.
R1 = bytes.fromhex("00000000 A58D0A 4EB1D8B1302E35592D338D0A 4EB2A0473030A0D830A05930A04D30B28D0A 4D33308D0A")
O1 = b"%\r\nN1X10.500Y-3.000\r\nN2X0.000Y0.000G00M02\r\nM30\r\n"  # the output: ASCII (P71 = 1), M30 generated
KEYS = bytes((0x48, 0x05, 0x02))  # key "P"; 05h no key code; 02h without its parity bit (ISO: 82h)


def values(rows: list[list[str]], index: int, direction: str | None = None) -> list[str]:
    return [v for row in rows if row[index] and (direction is None or row[0] == direction)
            for v in row[index].split("|")]


def test_dnc_transfers_and_keyboard_codes_decode(tmp_path: Path) -> None:
    needs_program("tshark")
    with Session(tmp_path, "poselesta") as sim:
        sim.ctl("set", "poselesta", "panel.mode", "EXTERNAL_OPERATION")
        sim.ctl("set", "poselesta", "panel.program", "20")
        sim.ctl("set", "poselesta", "v7.transfer", "input")
        with serial.Serial(sim.ports["poselesta.v7"], 1200, stopbits=2, timeout=5) as dnc:
            dnc.write(R1)
            deadline = time.monotonic() + 10
            while "done" not in sim.ctl("read", "poselesta", "v7.state"):
                assert time.monotonic() < deadline, "the read-in never ended"
            sim.ctl("set", "poselesta", "param.P71", "1")
            sim.ctl("set", "poselesta", "v7.transfer", "output")
            assert dnc.read(len(O1)) == O1
        with serial.Serial(sim.ports["poselesta.v8"], 1200, stopbits=2, timeout=5) as keyboard:
            keyboard.write(KEYS)
            keyboard.flush()
            deadline = time.monotonic() + 10  # all three in the capture before the simulator stops
            while json.loads(sim.ctl("line", "poselesta", "--port", "v8", "--json"))["bytes_in"] < len(KEYS):
                assert time.monotonic() < deadline, "the key codes never arrived"
    v7 = tshark_fields(tmp_path / "poselesta-v7.pcap", ["devsim.dir", "poselesta.block", "poselesta.n",
                                                         "poselesta.g", "poselesta.m", "poselesta.code",
                                                         "poselesta.leader", "devsim.port"])
    assert set(values(v7, 7)) == {"7"}
    assert values(v7, 1, "0") == ["%", "N1X10.5Y-3", "N2 G00 X0 Y0 M02", "M30"]
    assert values(v7, 1, "1") == ["%", "N1X10.500Y-3.000", "N2X0.000Y0.000G00M02", "M30"]
    assert values(v7, 2) == ["1", "2", "1", "2"] and values(v7, 3) == ["0", "0"]
    assert values(v7, 4) == ["2", "30", "2", "30"]
    assert set(values(v7, 5, "0")) == {"ISO (even parity in bit 7)"}
    assert set(values(v7, 5, "1")) == {"ASCII"}
    assert values(v7, 6) == ["4"]  # the NUL leader
    v8 = tshark_fields(tmp_path / "poselesta-v8.pcap", ["poselesta.key", "poselesta.key.valid",
                                                         "poselesta.parity_ok", "poselesta.key.display"])
    assert values(v8, 0) == ["0x48", "0x05", "0x02"]
    assert values(v8, 1) == ["1", "0", "1"]
    assert values(v8, 2) == ["1", "1", "0"]
    assert values(v8, 3) == ["0x49", "0x03"]  # what the keyboard diagnostic shows: the code + 1


def test_handshake_characters_and_parity_errors_in_a_block(tmp_path: Path) -> None:
    from devsim.devices.poselesta.codes import encode

    needs_program("tshark")
    block = encode("N10 G01 X-20.000\r\n", True)
    damaged = block[:4] + bytes((block[4] ^ 0x80,)) + block[5:]  # "G" with its parity bit flipped
    capture = write_pcap(tmp_path / "h.pcap", "poselesta", [("H>D", b"\x11" + damaged)], port=6)
    rows = tshark_fields(capture, ["poselesta.handshake", "poselesta.parity_errors", "poselesta.block", "poselesta.g"])
    assert rows == [["DC1 (XON)", "1", "N10 G01 X-20.000", "1"]]
