"""E-version frame count bit on the real pty (manual §4.4 "19244-E-Version"; spec §3.4, §3.9).

Checked by the helper gmse's sweep: a frame the card drops without answer (here a parameter
count that is no multiple of three, spec §3.5) is not taken, so it does not use up the FCB;
the host's next frame with the same FCB is new and executed, and its repeat is not.
"""

from __future__ import annotations

from typing import Any

from devsim.devices.gms96 import codec
from tests.gms96.test_link_options import letter

Q0 = "68 06 06 68 53 03 51 00 00 00 A7 16"


def test_a_frame_the_card_drops_does_not_use_up_the_fcb(plant_factory: Any) -> None:
    plant = plant_factory({"dil": {"protocol": "E"}})
    host = plant.host
    assert host.ask(Q0) == "E5"  # FCB = 0 (the first frame after power-on is taken)
    plant.idle()
    assert host.ask(letter("+", 1000, control=0x73)) == "E5"  # FCB = 1
    plant.idle()
    dropped = codec.encode(codec.LongFrame(0x53, 3, b"+\xe8\x03")).hex(" ")  # 2 parameter bytes
    assert host.silent(dropped)
    assert host.ask(letter("+", 1000, control=0x53)) == "E5"  # FCB = 0 again: new, executed
    plant.idle()
    assert plant.read("position_setpoint") == 2000
    assert host.ask(letter("+", 1000, control=0x53)) == "E5"  # its repeat: the same answer only
    plant.idle()
    assert plant.read("position_setpoint") == 2000
    assert host.ask(letter("+", 1000, control=0x73)) == "E5"  # toggled: executed
    plant.idle()
    assert plant.read("position_setpoint") == 3000
