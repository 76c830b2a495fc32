"""A SERS session through a real pty of ``devsim run sers --trace x.pcap``, decoded by tshark
with devsim's Lua dissectors: the addresses, parameter numbers and statements the host sent, the
answers, and the errno of each error message (the device sends only the text, manual §4.8.3.1)."""

from __future__ import annotations

import re
from pathlib import Path

import serial

from devsim.devices.sers import errors
from tests.support.programs import needs_program
from tests.wireshark.captures import Session, tshark_fields, write_pcap

ACK = re.compile(rb"\n(ok\d|pgm)\n\r|\n\*[^\n]*\n\r")
LINES = [b"#1P11?\r", b"#1V=1000\r", b"#V?\r", b"#1V=99999999\r", b"#1P9999?\r", b"#1FOO\r"]


def converse(port: serial.Serial, line: bytes) -> bytes:
    port.write(line)
    answer = b""
    while not ACK.search(answer):
        chunk = port.read(1)
        assert chunk, f"no acknowledgement to {line!r}, got {answer!r}"
        answer += chunk
    return answer


def test_a_sers_session_decodes_with_addresses_parameters_and_errnos(tmp_path: Path) -> None:
    needs_program("tshark")
    config = tmp_path / "sers.yaml"
    config.write_text("boot_time: 0\n")
    with Session(tmp_path, "sers", "--config", str(config)) as session:
        with serial.Serial(session.ports["sers"], 9600, timeout=5) as port:
            answers = [converse(port, line) for line in LINES]
    assert answers[0].endswith(b"P11=0\n\r\nok1\n\r")
    rows = tshark_fields(session.capture, ["devsim.dir", "sers.kind", "sers.address", "sers.param", "sers.errno",
                                           "sers.error", "sers.answer", "sers.value", "sers.ack"])
    host = [row for row in rows if row[0] == "0"]
    assert [row[2] for row in host] == ["1", "1", "", "1", "1", "1"]  # "#V?" names no address
    assert [row[3] for row in host] == ["11", "91", "91", "91", "9999", ""]  # V is P91 (an alias)
    device = "|".join(row[1] for row in rows if row[0] == "1").split("|")
    assert device.count("acknowledgement") == 3 and device.count("error message") == 3
    assert device.count("answer") == 2  # P11=0, V=1000U/min
    errnos = [int(n) for row in rows if row[0] == "1" and row[4] for n in row[4].split("|")]
    assert errnos == [errors.V_TOO_LARGE, errors.NO_PARAMETER, errors.STATEMENT_EXPECTED]
    texts = [t for row in rows if row[5] for t in row[5].split("|")]
    assert texts == ["V zu groß", "Parameter nicht vorhanden", "Anweisung erwartet"]
    values = dict(zip("|".join(r[6] for r in rows if r[6]).split("|"), "|".join(r[7] for r in rows if r[7]).split("|"),
                      strict=True))
    assert values == {"P11": "0", "V": "1000U/min"}


def test_an_answer_split_over_two_chunks_is_one_line(tmp_path: Path) -> None:
    needs_program("tshark")
    capture = write_pcap(tmp_path / "split.pcap", "sers", [
        ("H>D", b"#2P9999?\r"), ("D>H", b"#2P9999?\r\n*Parameter nicht"), ("D>H", b" vorhanden\n\r")])
    rows = tshark_fields(capture, ["sers.errno", "sers.error", "devsim.pending"])
    assert rows[1] == ["", "", "2a506172616d65746572206e69636874"]  # held back, shown as pending
    assert rows[2][:2] == [str(errors.NO_PARAMETER), "Parameter nicht vorhanden"]
