"""Memory under garbage (issue 32, item 2): a million bad telegrams leave every history a device
and its line keep bounded.  Fed in-process through the real face and the real telegram tap (the
same objects a pty feeds), the retained memory measured with tracemalloc between the first fifth
of the traced telegrams and all of them: what grows with traffic shows there, a bounded structure
does not.  tracemalloc triples the cost of what it traces, so the long feeds run their first part
untraced (the bounded histories fill there) and trace the rest."""

from __future__ import annotations

import gc
import random
import tracemalloc
from collections.abc import Callable

import pytest

from devsim.core.clock import VirtualClock
from devsim.core.framing import PLAIN
from devsim.core.registry import device_class
from devsim.devices.ip247 import Ip247Device
from devsim.devices.ip247.as511 import EVENTS_KEPT
from devsim.devices.sers.device import SersDevice
from devsim.transports.tap import MAX_BYTES, TelegramTap

TELEGRAMS = 1_000_000
BATCH = 1000
#: growth allowed over the traced telegrams after their first fifth (before the IP247 fix: ~50 MB
#: between the 200,000th and the 1,000,000th telegram)
GROWTH = 256 * 1024


def _growth(feed: Callable[[int], None], telegrams: int = TELEGRAMS, untraced: int = 0) -> int:
    """Bytes retained by ``feed`` between the first fifth of ``telegrams`` and all of them, traced
    after ``untraced`` telegrams more fed first."""
    feed(untraced)
    tracemalloc.start()
    try:
        feed(telegrams // 5)
        gc.collect()
        before = tracemalloc.get_traced_memory()[0]
        feed(telegrams - telegrams // 5)
        gc.collect()
        return tracemalloc.get_traced_memory()[0] - before
    finally:
        tracemalloc.stop()


def test_ip247_refused_and_abandoned_transactions_keep_bounded_memory() -> None:
    clock = VirtualClock()
    device = Ip247Device(clock=clock, config={"sys_id": {"module": 11}})
    clock.advance(1.0)  # the module runs after its 1 s start (spec §5.16)
    answers = bytearray()
    device.port("pg").attach(lambda data: answers.extend(data) if len(answers) < 64 else None)
    # STX, an unknown function (DLE NAK: refused); STX, a known one, then no DLE ACK (abandoned)
    batch = (b"\x02\xff" + b"\x02\x62\x00") * (BATCH // 2)

    def feed(telegrams: int) -> None:
        for _ in range(telegrams // BATCH):
            device.port("pg").feed(batch)
            clock.advance(0.001)

    assert _growth(feed, TELEGRAMS // 5, untraced=TELEGRAMS - TELEGRAMS // 5) < GROWTH  # (a million in all)
    link = device.face("pg").link
    assert len(link.events) <= 2 * EVENTS_KEPT and link.events[-1] == "abandoned: expected DLE ACK"
    assert not link.busy


def test_a_line_tap_decoding_garbage_without_line_ends_keeps_bounded_memory() -> None:
    """``devsim ctl telegrams`` and ``-v`` decode a SERS line by its framing: text never ended by
    CR/LF is shown, not kept (it grew and was decoded again on every chunk)."""
    tap = TelegramTap(None, decoder=SersDevice.ports[0].framing.decoder)
    chunk = b"#1P51?" * 5  # a host's garbage: no CR, no LF
    moment = [0.0]

    def feed(telegrams: int) -> None:
        for _ in range(telegrams // 5):
            moment[0] += 0.01
            tap.record("H>D", chunk, moment[0])

    assert _growth(feed, 100_000, untraced=400_000) < GROWTH  # (the rest grew 6 bytes a telegram)
    assert len(tap.telegrams) <= 200 and len(tap.decoders["H>D"]._rest) <= 512


def test_a_tap_keeps_no_telegram_longer_than_max_bytes_whatever_the_reads() -> None:
    """A pty read brings up to 4096 bytes, a TCP read up to 64 KiB: the tap cuts such a chunk into
    telegrams of at most :data:`MAX_BYTES`, as it cuts joined chunks (it kept each read whole, as
    hex and text: 200 telegrams of 64 KiB reads are ~90 MB per line; the soak's PCD4.H3, its three
    ports fed, grew 16 MB)."""
    tap = TelegramTap(None, decoder=SersDevice.ports[0].framing.decoder)
    rng = random.Random(32)
    reads = [rng.randbytes(4096) for _ in range(60)] + [rng.randbytes(65536)]
    for number, data in enumerate(reads):
        tap.record("H>D", data, number * 1.0)
    kept = [bytes.fromhex(telegram["hex"]) for telegram in tap.telegrams]
    assert len(kept) == 200 and max(len(data) for data in kept) <= MAX_BYTES
    assert max(len(telegram["text"]) for telegram in tap.telegrams) <= 4 * MAX_BYTES + 2
    assert b"".join(kept[-128:]) == reads[-1]  # the last read, all of it, in order
    assert b"".join(kept[:72]) == b"".join(reads[-10:-1])  # 8 telegrams each


@pytest.mark.parametrize("kind", ["sers", "gms96", "poselesta", "ip247", "pcd4h3"])
def test_every_port_of_every_kind_keeps_bounded_memory_under_garbage(kind: str) -> None:
    """Random bytes on every port (device and telegram tap with the port's decoders), device time
    moving: what is kept after 20,000 chunks per port is what was kept after 4,000."""
    clock = VirtualClock()
    device = device_class(kind)(clock=clock, name="d")
    clock.run_until(lambda: not device.booting, 30.0)
    taps = {}
    for spec in device.ports:
        device.port(spec.name).attach(lambda data: None)
        taps[spec.name] = TelegramTap(None, decoder=(spec.framing or PLAIN).decoder)
    rng = random.Random(kind)
    chunks = [rng.randbytes(rng.randrange(1, 64)) for _ in range(256)]

    def feed(count: int) -> None:
        for number in range(count // 5):
            for name, tap in taps.items():
                data = chunks[number % len(chunks)]
                device.port(name).feed(data)
                tap.record("H>D", data, clock.now())
            clock.advance(0.01)

    assert _growth(feed, 20_000) < GROWTH
