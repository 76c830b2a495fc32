"""Garbage and broken telegrams never crash the PCD (the issue's robustness rule; spec §9.2):
random bytes on the serial link, random telegrams with a correct CRC, random Ether-S-Bus frames;
afterwards the station still answers and the axis data are intact."""

from __future__ import annotations

import random
import struct

from devsim.core.clock import VirtualClock
from devsim.devices.pcd4h3 import Pcd4h3Device
from devsim.devices.pcd4h3.sbus import crc16, ether_frame, stuff

STATUS = bytes.fromhex("B5 00 01 1B DD FF")


def device() -> tuple[VirtualClock, Pcd4h3Device, list[bytes]]:
    clock = VirtualClock()
    pcd = Pcd4h3Device(clock=clock, config={"response_delay_ms": 0, "h3def": {"bar": 200, "baf": 200}})
    out: list[bytes] = []
    for name in pcd.port_names():
        pcd.port(name).attach(out.append)
    return clock, pcd, out


def test_random_bytes_and_random_valid_telegrams() -> None:
    rng = random.Random(7)
    clock, pcd, out = device()
    pcd.set("axis.1.DestP", 1234)
    for _ in range(3000):
        if rng.random() < 0.5:
            pcd.port("sbus").feed(bytes(rng.randrange(256) for _ in range(rng.randrange(1, 40))))
        else:
            command = rng.choice([0x00, 0x02, 0x03, 0x05, 0x06, 0x07, 0x0B, 0x0D, 0x0E, 0x1B, 0x1D, 0x20, 0x2F, 0x43,
                                  rng.randrange(256)])
            if command in (0x0E, 0x0B):  # keep the axis block itself out of the writes
                params = bytes((rng.randrange(1, 9),)) + struct.pack(">H", rng.choice([0, 500, 4000, 4095, 8191]))
                params += bytes(rng.randrange(256) for _ in range(rng.randrange(0, 12)))
            else:
                params = bytes(rng.randrange(256) for _ in range(rng.randrange(0, 6)))
            body = bytes((0xB5, 0, rng.choice([1, 1, 2, 255]), command)) + params
            pcd.port("sbus").feed(stuff(body + crc16(body).to_bytes(2, "big")))
        if rng.random() < 0.01:
            clock.advance(0.05)
    pcd.port("sbus").feed(b"\xb5")  # whatever was half received is abandoned
    out.clear()
    pcd.port("sbus").feed(STATUS)
    assert out and out[-1][:2] == b"\xb5\x01"
    assert pcd.read("axis.1.DestP") == 1234 and pcd.read("axis.1.KProp") == 150


def test_random_ether_frames() -> None:
    rng = random.Random(11)
    _clock, pcd, out = device()
    for _ in range(2000):
        payload = bytes((1, rng.randrange(256))) + bytes(rng.randrange(256) for _ in range(rng.randrange(0, 10)))
        frame = ether_frame(rng.choice([0, 1, 2]), rng.randrange(65536), rng.choice([0, 0, 1]), payload)
        if rng.random() < 0.3:
            frame = frame[: rng.randrange(len(frame))]
        pcd.port(rng.choice(["ether_udp", "ether_tcp"])).feed(frame)
    pcd.port("ether_tcp").host_disconnected()
    out.clear()
    pcd.port("ether_udp").feed(ether_frame(1, 9, 0, bytes((1, 0x1B))))
    assert out == [ether_frame(1, 9, 1, pcd.read("plc.status").encode())]  # (a random 43h may have stopped it)
