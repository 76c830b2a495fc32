"""The PG port's link layer: the AS511 procedure, device side (spec ip247.md §3.5; manual §2.2
names AS511 without defining it, the spec follows the public descriptions).

Pure and incremental, no clock and no I/O: :meth:`As511Link.feed` takes the bytes from the
programmer (PG) and returns the bytes to send back; the caller keeps the 500 ms inter-character
timeout on its clock while :attr:`As511Link.busy` and calls :meth:`As511Link.timeout` when it
expires.  One transaction (§3.5.2)::

    PG  02                        device  10 06          request to send / ready
    PG  <fn>                      device  02             (10 15: function refused)
    PG  10 06                     device  16 10 03       "accept"
    PG  10 06
    PG  <parameters> 10 04        device  10 06          (10 15: parameters refused)
                                  device  02             only with a data phase:
    PG  10 06                     device  <data> 10 03
    PG  10 06
                                  device  02             the end, always
    PG  10 06                     device  12 10 03
    PG  10 06

Inside parameter and data blocks every 10H byte is doubled (DLE transparency); a single DLE
followed by EOT, ETX, ACK or NAK is a control sequence.
"""

from __future__ import annotations

from collections.abc import Callable

import msgspec

from devsim.core.kit import Command, Table

__all__ = [
    "ACK", "DLE", "EOT", "ETX", "NAK", "STX", "As511Link", "Refused", "dle_double", "dle_undouble", "function_token",
]

STX, ETX, EOT, ACK, DLE, NAK = 0x02, 0x03, 0x04, 0x06, 0x10, 0x15
DLE_ACK, DLE_NAK, DLE_ETX, DLE_EOT = bytes((DLE, ACK)), bytes((DLE, NAK)), bytes((DLE, ETX)), bytes((DLE, EOT))
ACCEPT = bytes((0x16, DLE, ETX))  # "accept" after the function code
END = bytes((0x12, DLE, ETX))  # "end" of every transaction
TIMEOUT = 0.5  # seconds: no gap this long inside a transaction (§3.5.1)
#: The link keeps its last this many events (a host sending garbage must not grow it forever).
EVENTS_KEPT = 100


class Refused(msgspec.Struct, frozen=True):
    """The device refuses the parameters (DLE NAK in step 9)."""

    reason: str = ""


#: What a service answers: response data (a data phase follows), None (no data phase), Refused.
Reply = bytes | None | Refused


def function_token(code: int) -> str:
    """A PG function code as the tables name it: ``61H``."""
    return f"{code:02X}H"


def dle_double(data: bytes) -> bytes:
    """DLE transparency: every 10H twice."""
    return data.replace(b"\x10", b"\x10\x10")


def dle_undouble(data: bytes) -> bytes:
    """The receiver's side of :func:`dle_double` (a block without its DLE ETX/EOT)."""
    return data.replace(b"\x10\x10", b"\x10")


class As511Link:
    """One PG port's transaction state (the device is the slave).

    ``known(fn)`` says whether a function code exists (else DLE NAK right after it);
    ``service(fn, parameters)`` carries it out once the parameters are complete; a parameter block
    longer than ``most`` bytes (after DLE removal), or one with a single DLE followed by anything
    but DLE or EOT, gets DLE NAK instead, at its DLE EOT, and nothing is executed (spec §3.6.5);
    the bytes beyond are not kept.  ``events``
    collects what a host developer may want to know (``refused_function``, ``refused_parameters:
    <why>``, ``abandoned: <why>``): the last :data:`EVENTS_KEPT`; ``noted`` (if given) hears each
    as it happens."""

    def __init__(self, known: Callable[[int], bool], service: Callable[[int, bytes], Reply],
                 most: int = 1 << 16, noted: Callable[[str], None] | None = None) -> None:
        self.known, self.service, self.most = known, service, most
        self.noted = noted
        self.state = "idle"
        self.events: list[str] = []
        self._fn = 0
        self._block = bytearray()
        self._dle = False  # a DLE was the last byte (inside a block, or the first of DLE ACK)
        self._broken = ""  # why the parameter block will be refused at its DLE EOT
        self._data: bytes | None = None

    @property
    def busy(self) -> bool:
        """Inside a transaction: the 500 ms timeout runs (restarted by every byte)."""
        return self.state != "idle"

    def timeout(self) -> None:
        """500 ms without a byte inside a transaction: it is abandoned (§3.5.1)."""
        if self.busy:
            self._abandon("timeout")

    def feed(self, data: bytes) -> list[bytes]:
        out: list[bytes] = []
        for byte in data:
            self._byte(byte, out)
        return out

    # -- the steps (one reader per state, :data:`STATES`) ----------------------------------------------
    def _byte(self, byte: int, out: list[bytes]) -> None:
        STATES[self.state](self, byte, out)

    def _idle(self, byte: int, out: list[bytes]) -> None:
        if byte == STX:
            out.append(DLE_ACK)
            self.state = "function"
        # anything else between transactions is noise

    def _function(self, byte: int, out: list[bytes]) -> None:
        self._fn = byte
        if self.known(byte):
            out.append(bytes((STX,)))
            self.state = "ack_accept"
        else:
            out.append(DLE_NAK)
            self._note("refused_function")
            self.state = "idle"

    def _awaiting_ack(self, byte: int, out: list[bytes]) -> None:
        """Every other state waits for the PG's DLE ACK, then takes its step."""
        if not self._dle:
            if byte == DLE:
                self._dle = True
            else:
                self._abandon("expected DLE ACK")
            return
        self._dle = False
        if byte != ACK:
            self._abandon("DLE NAK" if byte == NAK else "expected DLE ACK")
            return
        ACKNOWLEDGED[self.state](self, out)

    def _send_accept(self, out: list[bytes]) -> None:
        out.append(ACCEPT)
        self.state = "ack_parameters"

    def _open_parameters(self, out: list[bytes]) -> None:
        self._block.clear()
        self._broken = ""
        self.state = "parameters"

    def _send_data(self, out: list[bytes]) -> None:
        assert self._data is not None
        out.append(dle_double(self._data) + DLE_ETX)
        self.state = "ack_data_done"

    def _send_stx(self, out: list[bytes]) -> None:
        out.append(bytes((STX,)))
        self.state = "ack_end"

    def _send_end(self, out: list[bytes]) -> None:
        out.append(END)
        self.state = "ack_final"

    def _finished(self, out: list[bytes]) -> None:
        self.state = "idle"

    def _parameter(self, byte: int, out: list[bytes]) -> None:
        if not self._dle:
            if byte == DLE:
                self._dle = True
            elif len(self._block) <= self.most:  # (one byte over says "too long")
                self._block.append(byte)
            return
        self._dle = False
        if byte == DLE:
            if len(self._block) <= self.most:
                self._block.append(DLE)  # a doubled DLE is one data byte
            return
        if byte != EOT:  # refused at the block's end, the next acknowledgement point (spec §3.6.5)
            self._broken = "a single DLE inside the parameters"
            return
        if self._broken:
            reply: Reply = Refused(self._broken)
        elif len(self._block) > self.most:
            reply = Refused("too long")
        else:
            reply = self.service(self._fn, bytes(self._block))
        if isinstance(reply, Refused):
            out.append(DLE_NAK)
            self._note(f"refused_parameters: {reply.reason}")
            self.state = "idle"
            return
        out.append(DLE_ACK)
        out.append(bytes((STX,)))
        self._data = reply
        self.state = "ack_data" if reply is not None else "ack_end"

    def _note(self, event: str) -> None:
        self.events.append(event)
        if len(self.events) > 2 * EVENTS_KEPT:
            del self.events[:-EVENTS_KEPT]
        if self.noted is not None:
            self.noted(event)

    def _abandon(self, why: str) -> None:
        self._note(f"abandoned: {why}")
        self.state = "idle"
        self._dle = False
        self._block.clear()
        self._data = None


Reader = Callable[[As511Link, int, list[bytes]], None]
Step = Callable[[As511Link, list[bytes]], None]

#: The link's states (spec §3.5.2): the reader of the next byte in each.
STATES: Table[Reader] = Table([
    Command("idle", As511Link._idle, "spec §3.5.2", "between transactions: STX opens one (DLE ACK)"),
    Command("function", As511Link._function, "spec §3.5.2", "the function code: STX if known, else DLE NAK"),
    Command("parameters", As511Link._parameter, "spec §3.5.2", "the parameter block up to DLE EOT"),
    *(Command(state, As511Link._awaiting_ack, "spec §3.5.2", "waiting for the PG's DLE ACK")
      for state in ("ack_accept", "ack_parameters", "ack_data", "ack_data_done", "ack_end", "ack_final")),
])
#: What the device does when the PG acknowledges (DLE ACK) in each waiting state (spec §3.5.2).
ACKNOWLEDGED: Table[Step] = Table([
    Command("ack_accept", As511Link._send_accept, "spec §3.5.2", "send \"accept\" 16 10 03"),
    Command("ack_parameters", As511Link._open_parameters, "spec §3.5.2", "the parameter block follows"),
    Command("ack_data", As511Link._send_data, "spec §3.5.2", "send the response data, DLE ETX"),
    Command("ack_data_done", As511Link._send_stx, "spec §3.5.2", "STX: the end follows"),
    Command("ack_end", As511Link._send_end, "spec §3.5.2", "send \"end\" 12 10 03"),
    Command("ack_final", As511Link._finished, "spec §3.5.2", "the transaction is complete"),
])
