"""Which operator jobs an IP247 axis takes (spec ip247.md §3.1, §3.2, §4.2)."""

from __future__ import annotations

import msgspec
import pytest

from devsim.devices.ip247.jobs import AxisView, Job, refusal

READY = AxisView(page=1, md_valid=True, reference_set=True, running=False, mode=4)
START, STOP, FORWARD, BACKWARD, TAKE_OVER = 1, 2, 3, 4, 5


@pytest.mark.parametrize(
    ("axis", "job", "error"),
    [
        (READY, Job(1, 1, FORWARD), None),  # jog forward
        (READY, Job(1, 1, START), 2),  # BA1 has no Start
        (READY, Job(4, 1, FORWARD), 46),  # a motion mode on the data channel
        (READY, Job(1, 18, START), 2),  # exists only in FB164
        (READY, Job(1, 3, START), 2),  # "frei"
        (msgspec.structs.replace(READY, md_valid=False), Job(1, 7, FORWARD), 14),  # no valid machine data
        (msgspec.structs.replace(READY, md_valid=False), Job(1, 4, START), None),  # BA4 always
        (msgspec.structs.replace(READY, md_valid=False), Job(1, 17, START), None),  # BA17 always
        (msgspec.structs.replace(READY, reference_set=False), Job(1, 6, START), 10),  # BA6 needs the reference
        (msgspec.structs.replace(READY, reference_set=False), Job(1, 7, FORWARD), None),  # BA7 does not
        (msgspec.structs.replace(READY, reference_set=False), Job(1, 8, START), 10),
        (READY, Job(1, 6, FORWARD), 2),  # linear axis: BA6 only with Start
        (msgspec.structs.replace(READY, rotary=True), Job(1, 6, FORWARD), None),
        (msgspec.structs.replace(READY, teach_in=True), Job(1, 8, START), 30),  # not in teach-in
        (msgspec.structs.replace(READY, teach_in=True), Job(1, 7, FORWARD), None),
        (msgspec.structs.replace(READY, teach_in=True), Job(1, 1, TAKE_OVER), None),  # store a teach-in block
        (READY, Job(1, 1, TAKE_OVER), 2),  # Übernahme in BA1 without teach-in
        (msgspec.structs.replace(READY, running=True, mode=7), Job(1, 7, STOP), None),  # Stopp while running
        (msgspec.structs.replace(READY, running=True, mode=7), Job(1, 4, START), None),  # BA4 stops the running mode
        (msgspec.structs.replace(READY, running=True, mode=7), Job(1, 6, START), 2),  # anything else: error 2
        (msgspec.structs.replace(READY, running=True, mode=1), Job(1, 2, FORWARD), None),  # jog 1 → jog 2
        (msgspec.structs.replace(READY, running=True, mode=1), Job(1, 1, FORWARD), 2),  # the same jog again
        (msgspec.structs.replace(READY, running=True, mode=8), Job(1, 20, 0), 4),  # machine data while running
        (READY, Job(4, 22, 0), None),  # program input on the data channel
        (READY, Job(2, 22, 0), 46),  # ... not on an axis page
        (READY, Job(4, 17, START), None),  # clear errors on the data channel
    ],
)
def test_the_preconditions_in_order(axis: AxisView, job: Job, error: int | None) -> None:
    assert refusal(axis, job) == error
