"""The kit's signal bank (devsim.core.signals): values, change events, and the layout (names,
kinds, positions) that devices declaring the same signals share (issue 31: a device's share)."""

from __future__ import annotations

import pytest

from devsim.core.signals import SignalBank

DECLARED = (("stop", "input", False, "STOP"), ("O1", "output", False, "output 1"), ("volts", "quantity", 24.0, ""))


def test_set_notifies_each_signals_listeners_then_the_banks_only_on_a_change() -> None:
    bank = SignalBank()
    bank.declare(DECLARED)
    heard: list[tuple] = []
    bank.subscribe("stop", lambda *change: heard.append(("stop", *change)))
    bank.subscribe_all(lambda *change: heard.append(("all", *change)))
    assert bank.set("stop", True) and not bank.set("stop", True)
    assert bank.set("volts", 12.0)
    assert heard == [("stop", "stop", False, True), ("all", "stop", False, True), ("all", "volts", 24.0, 12.0)]
    assert bank.snapshot() == {"stop": True, "O1": False, "volts": 12.0}
    assert bank.snapshot("output") == {"O1": False} and bank.names("input") == ["stop"]


def test_unsubscribe_and_a_quiet_initial_value() -> None:
    bank = SignalBank()
    bank.declare(DECLARED)
    heard: list[object] = []
    undo = bank.subscribe("O1", lambda *change: heard.append(change))
    bank.signal("O1").value = True  # an initial state: nobody is told
    assert bank.get("O1") is True and heard == []
    undo()
    bank.set("O1", False)
    assert heard == [] and bank.signal("O1").listeners == ()


def test_names_are_checked() -> None:
    bank = SignalBank()
    bank.declare(DECLARED)
    with pytest.raises(ValueError):
        bank.define("stop", "input", False)
    with pytest.raises(ValueError):
        SignalBank().declare(DECLARED + DECLARED[:1])
    for call in (lambda: bank.get("nope"), lambda: bank.set("nope", 1), lambda: bank.subscribe("nope", print)):
        with pytest.raises(KeyError, match="nope"):
            call()


def test_banks_that_declare_the_same_signals_share_their_layout_not_their_values() -> None:
    first, second = SignalBank(), SignalBank()
    for bank in (first, second):
        bank.declare(DECLARED)
        bank.define("extra", "input", 0)
    assert first._layout is second._layout
    first.set("extra", 1)
    assert (first.get("extra"), second.get("extra")) == (1, 0)
    other = SignalBank()
    other.declare(DECLARED[:2])
    assert other._layout is not first._layout and "volts" not in other
