"""Peers on V6 a plant can plug in instead of a host (spec poselesta.md Appendix A, §3.8): the
ELESTA cassette recorder Z2 / ZPS 020 (manual §2.6.2.2).  T2 records onto its tape what the
control sends after the 13 s leader; T3 plays the tape back into the control once the leader has
run (a host on the V6 pty may still send: both reach the read-in, as on a shared line)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from devsim.devices.poselesta.transfers import CASSETTE_LEADER

if TYPE_CHECKING:
    from devsim.devices.poselesta.cnc import PoselestaCnc

__all__ = ["Cassette"]


class Cassette:
    """The cassette recorder on V6: one tape, kept in the plant's memory across power cycles."""

    def __init__(self, cnc: PoselestaCnc) -> None:
        self.cnc = cnc
        self.tape = bytes.fromhex(cnc.nvram.get("cassette") or "")
        self._recording = b""
        self._timer: object | None = None
        cnc.listen("v6_out", self._heard)

    def _function(self) -> str:
        running = self.cnc.transfers.get("v6")
        return running.function.name if running is not None else ""

    def _heard(self, data: bytes) -> None:
        if self._function() == "T2":
            self._recording += data

    def started(self, name: str) -> None:
        """A V6 transfer starts: T2 begins a new recording, T3 plays after the leader."""
        if name == "T2":
            self._recording = b""
        elif name == "T3":
            self._timer = self.cnc.clock.call_later(CASSETTE_LEADER, self._play)

    def ended(self, name: str, state: str) -> None:
        if name == "T2" and state == "done":
            self.tape = self._recording
            self.cnc.nvram.put("cassette", self.tape.hex())
        if self._timer is not None and name == "T3":
            self._timer.cancel()  # type: ignore[attr-defined]
            self._timer = None

    def _play(self) -> None:
        self._timer = None
        if self._function() == "T3":
            self.cnc.port_input("v6", self.tape)

    def eject(self) -> None:
        self.tape = b""
        self.cnc.nvram.put("cassette", "")
