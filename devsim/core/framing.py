"""How a port's byte stream is cut into messages, described and matched: the kit's :class:`Framing`.

A kind declares it on each of its ports (:attr:`devsim.core.kit.PortDef.framing`); record and
replay, the telegram tap (``devsim ctl telegrams``, ``devsim monitor``) and anything else that
looks at a port's bytes take it from there, so that nothing outside the kind keeps a table of
kinds.  A port without one is recorded and replayed byte-exact, its host messages cut where the
device starts answering, and its telegrams carry no decoding.

* ``split(buffer)`` cuts the bytes a host sent into complete messages and the incomplete rest;
  ``None``: no framing known.
* ``decoder(direction)`` makes a stateful decoder of one direction (``"host"``: what the device
  receives, ``"device"``: what the host receives): fed each chunk, it returns the JSON-able
  descriptions of the messages the chunk completes.
* ``label(message)``: one decoded message (what the decoder returned for it) in a few characters,
  for the chunk labels of a plot (``M 20000`` for a GMS96 letter); ``None``: the plot shows a text
  message as its text and a described one by its fields.
* ``tolerances``: the ways a host's request may differ from a recorded one and still be the same
  request, tried in order after an exact match failed.  Each maps a message to a key; two
  messages match under a tolerance when their keys are equal.  A tolerance may also ``adapt``
  the recorded answer to the host's request (an Ether-S-Bus reply carries the request's
  sequence number).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol

import msgspec

__all__ = ["MAX_PARTIAL", "Decoder", "Framing", "PLAIN", "PlainDecoder", "Splitter", "Tolerance", "split_at"]

#: A decoder keeps at most this many bytes of an unfinished message; beyond, it reports them as
#: they are (a host sending garbage without a message end must not grow it forever).
MAX_PARTIAL = 512

#: bytes a host sent → (complete messages, the unfinished rest)
Splitter = Callable[[bytes], tuple[list[bytes], bytes]]


class Decoder(Protocol):
    """A stateful decoder of one direction of a port."""

    def feed(self, data: bytes) -> list[Any] | None: ...


class PlainDecoder:
    """The decoder of a port that declares no framing: decodes nothing."""

    def __init__(self, direction: str = "host") -> None:
        self.direction = direction

    def feed(self, data: bytes) -> list[Any] | None:
        return None


class Tolerance(msgspec.Struct, frozen=True):
    """A named way two requests count as the same: ``key(message)`` equal; ``adapt(request,
    answer)`` makes the recorded answer fit the host's request (``None``: sent as recorded)."""

    name: str
    key: Callable[[bytes], bytes]
    adapt: Callable[[bytes, bytes], bytes] | None = None


class Framing(msgspec.Struct, frozen=True):
    """How a port's messages are cut, described and matched (see the module docstring)."""

    split: Splitter | None = None
    decoder: Callable[[str], Decoder] = PlainDecoder
    tolerances: tuple[Tolerance, ...] = ()
    label: Callable[[Any], str] | None = None


#: A port that declares no framing.
PLAIN = Framing()


def split_at(buffer: bytes, ends: tuple[int, ...]) -> tuple[list[bytes], bytes]:
    """Messages that end after one of the ``ends`` bytes, and the unfinished rest."""
    out: list[bytes] = []
    start = 0
    for i, byte in enumerate(buffer):
        if byte in ends:
            out.append(buffer[start : i + 1])
            start = i + 1
    return out, buffer[start:]
