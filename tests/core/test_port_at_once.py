"""A port hands a chunk to its face's ``answer_at_once`` first (devsim/core/device.py): what it
returns leaves in one write and the face's ``feed`` never sees the chunk; None hands the chunk to
``feed``, whose answers leave in one write as before; a receive-only port sends nothing either
way, and a face without ``answer_at_once`` is fed every chunk."""

from __future__ import annotations

from typing import Any, ClassVar

from devsim.core.clock import VirtualClock
from devsim.core.device import Device, Face
from devsim.core.kit import PortDef


class _Face(Face):
    """Answers ``Q`` CR at once (``<Q>``); echoes anything else and answers each CR (two sends)."""

    __slots__ = ("fed",)

    def __init__(self, model: Any, port: Any) -> None:
        super().__init__(model, port)
        self.fed: list[bytes] = []

    def feed(self, data: bytes) -> None:
        self.fed.append(data)
        self.send(data)
        for _ in range(data.count(b"\r")):
            self.send(b"<ok>")

    def answer_at_once(self, data: bytes) -> bytes | None:
        return b"<Q>" if data == b"Q\r" else None


class _PlainFace(_Face):
    """The same face without the at-once answer."""

    __slots__ = ()
    answer_at_once = None  # type: ignore[assignment]


class _Device(Device):
    kind: ClassVar[str] = "at-once"
    ports: ClassVar[tuple[PortDef, ...]] = (PortDef("main", "the port"), PortDef("keys", "receive only", receive_only=True))
    face_classes: ClassVar[dict[str, Any]] = {"main": _Face, "keys": _Face}


class _PlainDevice(_Device):
    kind: ClassVar[str] = "at-once-plain"
    face_classes: ClassVar[dict[str, Any]] = {"main": _PlainFace}


def _writes(device: Device, port: str, chunks: list[bytes]) -> tuple[list[bytes], list[bytes]]:
    writes: list[bytes] = []
    device.port(port).attach(writes.append)
    for chunk in chunks:
        device.port(port).feed(chunk)
    return writes, device.face(port).fed  # type: ignore[attr-defined]


def test_a_chunk_answered_at_once_leaves_in_one_write_and_never_reaches_feed() -> None:
    writes, fed = _writes(_Device(clock=VirtualClock()), "main", [b"Q\r", b"A\r", b"Q\r"])
    assert writes == [b"<Q>", b"A\r<ok>", b"<Q>"]
    assert fed == [b"A\r"]


def test_a_receive_only_port_and_a_face_without_it_go_the_usual_way() -> None:
    writes, fed = _writes(_Device(clock=VirtualClock()), "keys", [b"Q\r", b"A\r"])
    assert writes == [] and fed == [b"Q\r", b"A\r"]
    writes, fed = _writes(_PlainDevice(clock=VirtualClock()), "main", [b"Q\r"])
    assert writes == [b"Q\r<ok>"] and fed == [b"Q\r"]
