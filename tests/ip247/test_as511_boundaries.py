"""The AS511 link at its limits, by property (spec ip247.md §3.5, §3.6.5).

A whole transaction is generated (a known or unknown function, parameters with DLE bytes in
them, a reply with data, without, or refused), the PG's side is played byte by byte or in any
chunks, and the device's answers are compared with the sequence of §3.5.2 written here as an
oracle; the parameter block is generated at and around the link's length limit, and the
acknowledgement the device waits for is replaced by everything else in every state.
"""

from __future__ import annotations

import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as hs

from devsim.devices.ip247.as511 import (
    EVENTS_KEPT,
    As511Link,
    Refused,
    dle_double,
    dle_undouble,
    function_token,
)

STX, ETX, EOT, ACK, DLE, NAK = 0x02, 0x03, 0x04, 0x06, 0x10, 0x15
PG_ACK = b"\x10\x06"
KNOWN = frozenset({0x01, 0x04, 0x10, 0x61})


def _link(reply: bytes | None | Refused, most: int = 1 << 16) -> tuple[As511Link, list[tuple[int, bytes]]]:
    calls: list[tuple[int, bytes]] = []

    def service(fn: int, parameters: bytes) -> bytes | None | Refused:
        calls.append((fn, parameters))
        return reply

    return As511Link(KNOWN.__contains__, service, most), calls


def _transaction(fn: int, parameters: bytes, reply: bytes | None | Refused,
                 most: int = 1 << 16) -> list[tuple[bytes, bytes]]:
    """The oracle (§3.5.2): each PG step and the device's answer to it."""
    steps = [(b"\x02", b"\x10\x06")]
    if fn not in KNOWN:
        return [*steps, (bytes((fn,)), b"\x10\x15")]
    steps += [(bytes((fn,)), b"\x02"), (PG_ACK, b"\x16\x10\x03"), (PG_ACK, b"")]
    block = parameters.replace(b"\x10", b"\x10\x10") + b"\x10\x04"
    if isinstance(reply, Refused) or len(parameters) > most:
        return [*steps, (block, b"\x10\x15")]
    steps.append((block, b"\x10\x06\x02"))
    if reply is not None:
        steps += [(PG_ACK, reply.replace(b"\x10", b"\x10\x10") + b"\x10\x03"), (PG_ACK, b"\x02")]
    return [*steps, (PG_ACK, b"\x12\x10\x03"), (PG_ACK, b"")]


REPLIES = hs.one_of(hs.none(), hs.just(Refused("no")), hs.binary(max_size=12).map(lambda b: b + b"\x10"[: len(b) % 2]))
PARAMETERS = hs.binary(max_size=12).map(lambda b: b.replace(b"\x01", b"\x10"))


@settings(max_examples=300, deadline=None)
@given(hs.sampled_from([*KNOWN, 0x00, 0x02, 0x62, 0xFF]), PARAMETERS, REPLIES, hs.integers(1, 7))
@example(0x61, b"\x10", b"\x10", 1)
def test_a_transaction_step_by_step_and_in_chunks(fn: int, parameters: bytes, reply: bytes | None | Refused,
                                                  size: int) -> None:
    steps = _transaction(fn, parameters, reply)
    link, calls = _link(reply)
    for sent, answer in steps:
        assert b"".join(link.feed(sent)) == answer
    assert not link.busy
    executed = fn in KNOWN
    assert calls == ([(fn, parameters)] if executed else [])
    chunked, _ = _link(reply)
    wire = b"".join(sent for sent, _answer in steps)
    got = b"".join(b"".join(chunked.feed(wire[i : i + size])) for i in range(0, len(wire), size))
    assert got == b"".join(answer for _sent, answer in steps)
    assert chunked.events == ([] if executed and not isinstance(reply, Refused) else
                              ["refused_function"] if not executed else [f"refused_parameters: {reply.reason}"])


@pytest.mark.manual("§3.6.5", "a parameter block longer than the device takes is refused with DLE NAK")
@settings(max_examples=200, deadline=None)
@given(hs.integers(1, 12), hs.integers(-2, 2), hs.booleans())
@example(4, 0, True)  # exactly the limit, DLE bytes in it
@example(4, 1, False)  # one over
def test_the_parameter_block_at_its_length_limit(most: int, off: int, dles: bool) -> None:
    parameters = bytes([DLE if dles and i % 2 else 0x41 for i in range(max(0, most + off))])
    steps = _transaction(0x61, parameters, None, most)
    link, calls = _link(None, most)
    for sent, answer in steps:
        assert b"".join(link.feed(sent)) == answer
    assert calls == ([(0x61, parameters)] if len(parameters) <= most else [])
    assert link.events == ([] if len(parameters) <= most else ["refused_parameters: too long"])
    assert not link.busy


STATES_BEFORE = {  # PG bytes that bring a link (reply with data) into each waiting state
    "ack_accept": b"\x02\x61",
    "ack_parameters": b"\x02\x61\x10\x06",
    "ack_data": b"\x02\x61\x10\x06\x10\x06\x10\x04",
    "ack_data_done": b"\x02\x61\x10\x06\x10\x06\x10\x04\x10\x06",
    "ack_end": b"\x02\x61\x10\x06\x10\x06\x10\x04\x10\x06\x10\x06",
    "ack_final": b"\x02\x61\x10\x06\x10\x06\x10\x04\x10\x06\x10\x06\x10\x06",
}


@settings(max_examples=300, deadline=None)
@given(hs.sampled_from(sorted(STATES_BEFORE)), hs.integers(0, 255), hs.booleans())
@example("ack_final", NAK, True)
@example("ack_accept", ACK, False)
def test_anything_but_dle_ack_abandons_the_transaction(state: str, byte: int, after_dle: bool) -> None:
    link, _calls = _link(b"DATA")
    link.feed(STATES_BEFORE[state])
    assert link.state == state and link.busy
    wrong = bytes((DLE, byte)) if after_dle else bytes((byte,))
    if wrong in (PG_ACK, b"\x10"):
        return  # the acknowledgement itself (or its first half)
    assert link.feed(wrong) == []
    assert not link.busy
    assert link.events[-1] == ("abandoned: DLE NAK" if after_dle and byte == NAK else "abandoned: expected DLE ACK")
    assert b"".join(link.feed(b"\x02")) == b"\x10\x06"  # the next transaction opens


@settings(max_examples=100, deadline=None)
@given(hs.integers(0, 255).filter(lambda b: b not in (DLE, EOT)))
def test_a_single_dle_inside_the_parameters_is_refused_at_the_blocks_end(byte: int) -> None:
    """Spec §3.6.5: an undoubled DLE followed by an unexpected byte gets DLE NAK at the next
    acknowledgement point (the parameter block's DLE EOT); nothing is executed."""
    link, calls = _link(None)
    link.feed(b"\x02\x61\x10\x06\x10\x06AB")
    assert link.feed(bytes((DLE, byte))) == [] and link.busy
    assert link.feed(b"CD\x10\x10E\x10\x04") == [b"\x10\x15"] and not link.busy and calls == []
    assert link.events == ["refused_parameters: a single DLE inside the parameters"]
    assert b"".join(link.feed(b"\x02")) == b"\x10\x06"  # the next transaction opens


def test_the_timeout_abandons_only_a_transaction() -> None:
    link, _calls = _link(None)
    link.timeout()
    assert link.events == []
    link.feed(b"\x02")
    link.timeout()
    assert link.events == ["abandoned: timeout"] and not link.busy


@pytest.mark.parametrize("refusals", [EVENTS_KEPT, 2 * EVENTS_KEPT, 2 * EVENTS_KEPT + 1, 5 * EVENTS_KEPT])
def test_the_events_kept_are_bounded_and_the_last(refusals: int) -> None:
    link, _calls = _link(None)
    for _ in range(refusals):
        link.feed(b"\x02\xff")
    link.feed(b"\x02\x00")
    kept = 0  # the rule: the list grows to twice EVENTS_KEPT, then keeps the last EVENTS_KEPT
    for _ in range(refusals + 1):
        kept = kept + 1 if kept < 2 * EVENTS_KEPT else EVENTS_KEPT
    assert len(link.events) == kept <= 2 * EVENTS_KEPT
    assert link.events[-1] == "refused_function"


@settings(max_examples=200, deadline=None)
@given(hs.binary(max_size=20).map(lambda b: b.replace(b"\x01", b"\x10")))
def test_dle_doubling_round_trip(data: bytes) -> None:
    doubled = dle_double(data)
    assert len(doubled) == len(data) + data.count(DLE)
    assert dle_undouble(doubled) == data


@pytest.mark.parametrize(("code", "token"), [(0x00, "00H"), (0x0A, "0AH"), (0x61, "61H"), (0xFF, "FFH")])
def test_function_tokens(code: int, token: str) -> None:
    assert function_token(code) == token
