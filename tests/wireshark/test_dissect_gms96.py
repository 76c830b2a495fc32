"""A GMS96 session through a real pty of ``devsim run gms96 --trace x.pcap``, decoded by tshark
with devsim's Lua dissectors (link fields and the GMS96 commands, manual M §2.3), and compared
with Wireshark's own IEC 60870-5-101 dissector on the link fields of the frames it reads."""

from __future__ import annotations

from pathlib import Path

import serial

from devsim.devices.gms96 import codec
from devsim.devices.gms96.client import Gms96Client
from tests.support.programs import needs_program
from tests.wireshark.captures import Session, as_tcp, tshark_fields, write_pcap

ADDRESS = 3  # the card's default DIL address (manual §2.2)
BAD_CHECKSUM = bytes.fromhex("10 01 03 05 16")  # #1 to address 3 with checksum 05h (04h is right): no answer


def session(tmp_path: Path) -> Path:
    """N15 read, written and read again, the status T3;0, the #1 status Kurzsatz, #9 override 50 %,
    an unknown N parameter (answered E5h: no data), a frame with a wrong checksum (no answer)."""
    with Session(tmp_path, "gms96") as sim, serial.Serial(sim.ports["gms96"], 9600, timeout=3) as port:
        card = Gms96Client(port, ADDRESS, timeout=3)
        assert card.read(5, 15)[0] == ord("N")
        assert card.send_letter("N", 250, 15) == codec.SingleChar(codec.ACK)
        assert card.read(5, 15)[1] == 250
        card.read(3, 0)
        card.status()
        card.override(50)
        assert card.send_letter("T", 5, 99) == codec.SingleChar(codec.ACK)
        assert card.exchange(BAD_CHECKSUM) is None
    return sim.capture


def column(rows: list[list[str]], index: int, direction: str) -> list[str]:
    return [value for row in rows if row[0] == direction for value in row[index].split("|") if row[index]]


def test_a_gms96_session_decodes_with_commands_parameters_and_answers(tmp_path: Path) -> None:
    needs_program("tshark")
    capture = session(tmp_path)
    rows = tshark_fields(capture, ["devsim.dir", "gms96.address", "gms96.command", "gms96.p1", "gms96.p2",
                                   "gms96.n", "gms96.short", "gms96.override", "gms96.identifier", "gms96.value",
                                   "gms96.checksum.ok", "gms96.start"])
    assert set(column(rows, 1, "0")) == {str(ADDRESS)}
    assert column(rows, 2, "0") == ["T", "N", "T", "T", "T"]
    assert column(rows, 3, "0") == ["5", "250", "5", "3", "5"]
    assert column(rows, 5, "0") == ["15", "15", "15", "99"]  # the N parameter of T5 (P2) and of N (P2)
    assert column(rows, 6, "0") == ["1", "9", "1"]  # #1, #9, and the #1 with the wrong checksum
    assert column(rows, 7, "0") == ["50"]
    assert column(rows, 8, "1") == ["0x4e", "0x4e"]  # 'N': the answers to T5;15
    assert column(rows, 9, "1") == ["84", "250"]  # N15's default, then the value written
    assert column(rows, 10, "0")[-1] == "0" and set(column(rows, 10, "1")) == {"1"}
    assert column(rows, 11, "1").count("0xe5") == 3  # N, #9 and the unknown N99 (no data)


def test_the_link_fields_agree_with_wiresharks_iec60870_101(tmp_path: Path) -> None:
    needs_program("tshark")
    capture = session(tmp_path)
    ours = tshark_fields(capture, ["frame.number", "gms96.start", "gms96.length", "gms96.control",
                                   "gms96.address", "gms96.checksum"])
    theirs = tshark_fields(as_tcp(capture, tmp_path / "tcp.pcap"),
                           ["frame.number", "iec60870_101.header", "iec60870_101.length", "iec60870_101.ctrlfield",
                            "iec60870_101.linkaddr", "iec60870_101.checksum", "iec60870_101.stopchar"],
                           lua=False, options=("-d", "tcp.port==2404,iec60870_101"))
    compared = 0
    for mine, builtin in zip(ours, theirs, strict=True):
        number, header, length, control, address, cs, stop = builtin
        if not control or stop not in ("", "0x16"):
            continue  # not a frame it reads (E5h has no fields; a Kurzsatz with AE octets it misreads)
        assert mine[0] == number
        expected = [header.split("|")[0], length, control, address] + ([cs] if stop == "0x16" else [])
        assert mine[1 : 1 + len(expected)] == expected, (number, mine, builtin)
        compared += 1
    assert compared >= 8, (ours, theirs)


def test_a_frame_split_over_two_reads_is_reassembled(tmp_path: Path) -> None:
    needs_program("tshark")
    frame = codec.encode(codec.LongFrame(codec.control_host(1), ADDRESS, codec.letter("N", 250, 15)))
    capture = write_pcap(tmp_path / "split.pcap", "gms96", [("H>D", frame[:5]), ("H>D", frame[5:]),
                                                            ("D>H", bytes([codec.ACK]))])
    rows = tshark_fields(capture, ["gms96.command", "gms96.p1", "gms96.n", "devsim.pending", "gms96.checksum.ok"])
    assert rows[0] == ["", "", "", frame[:5].hex(), ""]
    assert rows[1] == ["N", "250", "15", "", "1"]


def test_an_answer_names_the_query_it_answers(tmp_path: Path) -> None:
    """The answer to T5;15 is N15's value (a later T5;99 does not change it, also in tshark's
    second pass); a Kurzsatz answering a letter command is the NACK of a full queue (link option
    ``on_queue_full: nack``), one answering #1 is the status byte K."""
    needs_program("tshark")

    def long(*data: int) -> bytes:
        return codec.encode(codec.LongFrame(codec.control_host(1), ADDRESS, codec.letter("T", *data)))

    chunks = [("H>D", long(5, 15)), ("D>H", codec.encode(codec.t_reply(ADDRESS, 0x4E, codec.to_s24(84)))),
              ("H>D", long(5, 99)), ("D>H", bytes([codec.ACK])),
              ("H>D", codec.encode(codec.LongFrame(codec.control_host(0), ADDRESS, codec.letter("A", 100)))),
              ("D>H", codec.encode(codec.ShortFrame(0x01, ADDRESS))),
              ("H>D", codec.encode(codec.short_command(1, ADDRESS))), ("D>H", codec.encode(codec.k_frame(0x80, ADDRESS, 23)))]
    capture = write_pcap(tmp_path / "t.pcap", "gms96", chunks)
    fields = ["gms96.n", "gms96.value", "gms96.nack", "gms96.k", "gms96.mb4"]
    once = tshark_fields(capture, fields)
    assert once[1][:2] == ["15", "84"]
    assert once[5][2:4] == ["1", ""] and once[7][2:] == ["", "0x82", "23"]
    assert tshark_fields(capture, fields, options=("-2",)) == once
