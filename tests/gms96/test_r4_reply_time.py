"""FT1.2 rule R4 when the card has answered behind the error (spec §3.2, §3.4, §3.10).

Found by the E-version sweep with non-ASCII bytes (helper gmse): a valid ``T0`` with one byte
80h..FFh glued behind its end byte was answered, but the host's next ``T0``, sent as soon as that
answer was in, was lost in 144 of 147 cases -- the stray byte armed the 33-bit-time idle, and the
simulator's answer took no time on the line.  On the real RS422 line the host hears the whole
answer first (half duplex, spec §3.4): a ``T`` answer is 10 characters, 110 bit times at the DIL
baud rate, plus the response delay, so the line has long been idle when the next frame comes.
"""

from __future__ import annotations

from tests.gms96.conftest import Plant
from tests.gms96.test_link_options import K_IDLE, STATUS, letter


def test_r4_a_frame_after_the_answer_to_a_frame_with_a_stray_byte_behind_is_taken(card: Plant) -> None:
    host = card.host
    answer = host.ask(f"{letter('T', 0)} FF")  # the frame is whole: answered; FFh arms R4
    assert answer.startswith("68 06 06 68 08 03 40")
    assert sum(card.read("link_errors").values()) >= 1  # the stray byte was seen as an error
    assert host.ask(letter("T", 0, control=0x73)) == answer  # no advance(): the answer's own line time
    assert host.ask(STATUS) == K_IDLE


def test_r4_still_holds_when_no_answer_came_between(card: Plant) -> None:
    """The rule itself is unchanged: a frame glued to the error, with no answer between, is lost."""
    host = card.host
    assert host.silent(f"{letter('T', 0)[:-6]} FF {STATUS}")  # T0 broken by FFh, then #1 at once
    assert card.read("link_errors").get("not_idle", 0) >= 1
