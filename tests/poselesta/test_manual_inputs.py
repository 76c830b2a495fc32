"""Manual §2.3 (control inputs V19–V24) statement by statement, through the control API of a
served device on the virtual clock: the input delay, the diagnostic page P79 N5 and the function
keys the screen shows for NC-Stop and NC-Start."""

from __future__ import annotations

from typing import Any

import pytest

#: §2.3: "Zeitverzögerung L ---> H: 2,5 ... 15 ms + ~25 ms; H ---> L: 15 ... 50 ms Rechenzeit".
RISE = (0.0025 + 0.025, 0.015 + 0.025)
FALL = (0.015, 0.050)


@pytest.fixture
def cnc(devsim_device):  # noqa: ANN001, ANN201
    cnc = devsim_device("poselesta")
    cnc.advance(0.1)
    return cnc


def shown(cnc: Any, name: str) -> Any:
    """A point as ``devsim ctl state`` and the monitor show it (the nested state)."""
    node = cnc.state()
    for part in name.split("."):
        node = node[part]
    return node


def _inputs_page(cnc: Any) -> None:
    cnc.set("panel.mode", "PROGRAM_ENTRY")
    cnc.set("panel.diagnostic", 5)


@pytest.mark.manual("§2.3", "Zeitverzögerung L ---> H: 2,5 ... 15 ms + ~25 ms")
def test_an_input_going_high_reaches_the_control_within_the_manuals_delay(cnc: Any) -> None:
    _inputs_page(cnc)
    cnc.set("input.rapid", True)  # V21/6, port 1 B bit 1
    assert cnc.read("input.rapid") is True  # the terminal
    cnc.advance(RISE[0] - 0.0005)
    assert cnc.read("diagnostics.inputs")["1B"] & 0x02 == 0  # the control has not seen it yet
    cnc.advance(RISE[1] - RISE[0] + 0.001)
    assert cnc.read("diagnostics.inputs")["1B"] & 0x02 == 0x02


@pytest.mark.manual("§2.3", "Zeitverzögerung H ---> L: 15 ... 50 ms Rechenzeit")
def test_an_input_going_low_reaches_the_control_within_the_manuals_delay(cnc: Any) -> None:
    _inputs_page(cnc)
    cnc.set("input.nc_stop", False)  # V19/1, port 4 B bit 3
    cnc.advance(FALL[0] - 0.0005)
    assert cnc.read("diagnostics.inputs")["4B"] & 0x08 == 0x08
    cnc.advance(FALL[1] - FALL[0] + 0.001)
    assert cnc.read("diagnostics.inputs")["4B"] & 0x08 == 0


@pytest.mark.manual("§2.3", "Zeitverzögerung L ---> H (the delay is a configuration key, input_rise_ms)")
def test_the_input_delay_is_configured(devsim_device) -> None:  # noqa: ANN001
    cnc = devsim_device("poselesta", {"input_rise_ms": 10})
    cnc.advance(0.1)
    _inputs_page(cnc)
    cnc.set("input.rapid", True)
    cnc.advance(0.0095)
    assert cnc.read("diagnostics.inputs")["1B"] & 0x02 == 0
    cnc.advance(0.001)
    assert cnc.read("diagnostics.inputs")["1B"] & 0x02 == 0x02


@pytest.mark.manual("§2.3.3", "NC-Start V19/3: In den Betriebsarten Automatik-Folgesatz … wird damit das Programm "
                    "gestartet (after the input delay of §2.3)")
def test_the_external_nc_start_starts_the_program_after_the_input_delay(cnc: Any) -> None:
    cnc.set("program.P20", "N1 G00 X10")
    cnc.set("panel.program", 20)
    cnc.set("panel.mode", "AUTO_CONTINUOUS")
    cnc.set("input.nc_start", True)
    cnc.advance(RISE[0] - 0.0005)
    assert cnc.read("program.state") == "IDLE"
    cnc.advance(RISE[1] - RISE[0] + 0.001)
    assert cnc.read("program.state") != "IDLE"


# -- §2.3.25 the input page P79 N5 ------------------------------------------------------------------
@pytest.mark.manual("§2.3.25", "Diagnose (P79, N5): Dies ist nur in der Betriebsart Programmeingabe möglich")
def test_the_input_page_exists_only_in_program_entry(cnc: Any) -> None:
    assert cnc.read("diagnostics.inputs") is None and cnc.read("diagnostics.input_screen") == ""
    with pytest.raises(ValueError, match="PROGRAM_ENTRY"):
        cnc.set("panel.diagnostic", 5)
    assert cnc.read("diagnostics.inputs") is None


@pytest.mark.manual("§2.3.25", "Anwahl: P 79 N 5; Abschluss: Betriebsart")
def test_a_mode_key_ends_the_input_page(cnc: Any) -> None:
    _inputs_page(cnc)
    assert cnc.read("diagnostics.inputs") is not None
    assert shown(cnc, "diagnostics.input_screen").startswith("Port 1 EIN ")
    cnc.set("panel.mode", "PROGRAM_ENTRY")  # the mode key, even of the same mode
    assert cnc.read("diagnostics.inputs") is None
    assert shown(cnc, "diagnostics.input_screen") == ""


@pytest.mark.manual("§2.3.25", "Ein Eingang auf H-Level wird auf dem Bildschirm mit 1 und ein Eingang auf L-Level "
                    "mit 0 dargestellt (Port 4 B 5 = V19/3 NC-Start)")
def test_the_input_page_shows_what_the_control_sees(cnc: Any) -> None:
    _inputs_page(cnc)
    cnc.set("input.nc_start", True)
    assert cnc.read("diagnostics.input_screen").splitlines()[3] == "Port 4 EIN 01100000 00011000"
    cnc.advance(RISE[1])
    assert cnc.read("diagnostics.input_screen").splitlines()[3] == "Port 4 EIN 01100000 00111000"
    assert shown(cnc, "diagnostics.input_screen") == cnc.read("diagnostics.input_screen")


@pytest.mark.manual("§2.3.26", "Diagnose P 79, N 7 (pots); Abschluss: Betriebsart")
def test_the_pot_page_is_shown_from_p79_n7_until_a_mode_key(cnc: Any) -> None:
    assert cnc.read("diagnostics.pots") is None
    cnc.set("panel.mode", "PROGRAM_ENTRY")
    cnc.set("panel.diagnostic", 7)
    assert cnc.read("diagnostics.pots") == ["FF", "AA"]  # 00 = 0 V, FF = +10 V; 6.667 V
    cnc.set("panel.mode", "MANUAL")
    assert cnc.read("diagnostics.pots") is None


# -- §2.3.1, §2.3.3 the function keys on the screen ---------------------------------------------------
@pytest.mark.manual("§2.3.3", "Solange der NC-Start wirksam ist, wird die entsprechende Funktionstaste am Bildschirm "
                    "abgebildet")
def test_the_screen_shows_the_nc_start_key_while_v19_3_is_high(cnc: Any) -> None:
    assert shown(cnc, "panel.function_keys") == []
    cnc.set("input.nc_start", True)
    cnc.advance(RISE[1])
    assert shown(cnc, "panel.function_keys") == ["NC-START"]
    cnc.set("input.nc_start", False)
    cnc.advance(FALL[1])
    assert cnc.read("panel.function_keys") == []


@pytest.mark.manual("§2.3.1", "Solange der NC-Stop wirksam ist, wird die entsprechende Funktionstaste am Bildschirm "
                    "abgebildet. NC-Stop ist im Handbetrieb unwirksam.")
def test_the_screen_shows_the_nc_stop_key_while_it_is_effective(cnc: Any) -> None:
    cnc.set("input.nc_stop", False)
    cnc.advance(FALL[1])
    assert cnc.read("panel.function_keys") == []  # MANUAL: NC-Stop has no effect
    cnc.set("panel.mode", "AUTO_CONTINUOUS")
    assert shown(cnc, "panel.function_keys") == ["NC-STOP"]
