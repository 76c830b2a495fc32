"""The AS511 link layer of the IP247's PG port (spec ip247.md §3.5, vectors of §3.6.7)."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as hs

from devsim.devices.ip247.as511 import As511Link, Refused, dle_double, dle_undouble

SYS_ID = bytes.fromhex("00 04 46 00 00 00 00 00 49 50 32 34 37 20 41 30 32 2E 31 20 00 0B 00 01 00 00")


def link(replies: dict[int, object] | None = None) -> tuple[As511Link, list[tuple[int, bytes]]]:
    calls: list[tuple[int, bytes]] = []
    table = {0x64: SYS_ID, 0x61: None, 0x65: Refused("no such record")} if replies is None else replies

    def service(fn: int, parameters: bytes) -> object:
        calls.append((fn, parameters))
        return table[fn]

    return As511Link(lambda fn: fn in table, service), calls  # type: ignore[arg-type]


def exchange(device: As511Link, steps: list[tuple[str, str]]) -> None:
    """Each step: what the PG sends, what the device must answer (hex)."""
    for sent, answer in steps:
        assert b"".join(device.feed(bytes.fromhex(sent))).hex(" ") == bytes.fromhex(answer).hex(" "), sent


def test_vector_a_reads_the_sys_id_in_one_transaction() -> None:
    """§3.6.7 (a), byte for byte."""
    device, calls = link()
    exchange(device, [
        ("02", "10 06"),
        ("64", "02"),
        ("10 06", "16 10 03"),
        ("10 06", ""),
        ("04 46 00 00 10 04", "10 06 02"),
        ("10 06", SYS_ID.hex() + "10 03"),
        ("10 06", "02"),
        ("10 06", "12 10 03"),
        ("10 06", ""),
    ])
    assert calls == [(0x64, bytes.fromhex("04 46 00 00"))] and not device.busy


def test_no_data_phase_and_refusals() -> None:
    """A service without response data ends at once; vector (f): an unknown function code is
    refused right after it; refused parameters get DLE NAK and end the transaction."""
    device, _ = link()
    exchange(device, [("02", "10 06"), ("61", "02"), ("10 06", "16 10 03"), ("10 06", ""),
                      ("01 08 10 04", "10 06 02"), ("10 06", "12 10 03"), ("10 06", "")])
    exchange(device, [("02", "10 06"), ("18", "10 15")])
    assert device.events == ["refused_function"] and not device.busy
    exchange(device, [("02", "10 06"), ("65", "02"), ("10 06", "16 10 03"), ("10 06", ""), ("10 04", "10 15")])
    assert not device.busy


def test_whoever_listens_hears_each_event_as_it_happens() -> None:
    """``noted`` (the PG face passes the device's event log) hears what ``events`` keeps, when it happens."""
    heard: list[str] = []
    device = As511Link(lambda fn: fn == 0x65, lambda fn, parameters: Refused("no such record"), noted=heard.append)
    exchange(device, [("02", "10 06"), ("18", "10 15")])
    assert heard == ["refused_function"]
    exchange(device, [("02", "10 06"), ("65", "02"), ("10 06", "16 10 03"), ("10 06", ""), ("10 04", "10 15")])
    assert heard == device.events == ["refused_function", "refused_parameters: no such record"]


def test_vector_d_dle_doubling_both_ways() -> None:
    """§3.6.7 (d): program number 16 in a request is sent as 10 10; 4112 (00001010H) as
    00 00 10 10 10 10 in a response."""
    device, calls = link({0x64: bytes.fromhex("00 00 10 10")})
    exchange(device, [("02", "10 06"), ("64", "02"), ("10 06", "16 10 03"), ("10 06", ""),
                      ("01 45 10 10 00 10 04", "10 06 02"), ("10 06", "00 00 10 10 10 10 10 03")])
    assert calls == [(0x64, bytes.fromhex("01 45 10 00"))]
    assert dle_double(bytes.fromhex("00 00 10 10")) == bytes.fromhex("00 00 10 10 10 10")


def test_a_host_that_vanishes_or_says_nak_leaves_the_link_ready() -> None:
    """A timeout or a DLE NAK abandons the transaction; the next STX starts a fresh one."""
    device, _ = link()
    exchange(device, [("02", "10 06"), ("64", "02")])
    device.timeout()
    assert not device.busy and device.events == ["abandoned: timeout"]
    exchange(device, [("02", "10 06"), ("64", "02"), ("10 15", "")])
    assert not device.busy and device.events[-1] == "abandoned: DLE NAK"
    exchange(device, [("77 02", "10 06")])  # noise before STX is ignored


@settings(max_examples=300, deadline=None)
@given(noise=hs.binary(max_size=200), payload=hs.binary(max_size=40))
def test_any_bytes_then_a_clean_transaction_works(noise: bytes, payload: bytes) -> None:
    """Garbage never raises; after a timeout a well-formed transaction always succeeds, and
    DLE-doubled parameters arrive exactly."""
    device, calls = link({0x64: b"\x10" + payload})
    device.feed(noise)
    device.timeout()
    steps = [bytes.fromhex(s) for s in ("02", "64", "10 06", "10 06")] + [dle_double(payload) + b"\x10\x04"]
    answers = [b"".join(device.feed(step)) for step in steps]
    assert answers[:3] == [b"\x10\x06", b"\x02", b"\x16\x10\x03"] and answers[4] == b"\x10\x06\x02"
    assert calls[-1] == (0x64, payload)
    data = b"".join(device.feed(b"\x10\x06"))
    assert dle_undouble(data[:-2]) == b"\x10" + payload and data.endswith(b"\x10\x03")
