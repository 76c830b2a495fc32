"""The discrete signals the host side of the POSELESTA touches (manual §2.3.11, §2.4.5, §2.4.9,
§2.6.2, §2.6.3; spec poselesta.md §2.5, §2.6, §3.10, §3.11), as electrical levels (True = H)."""

from __future__ import annotations

from devsim.core.kit import SignalDef

__all__ = ["SIGNALS"]

SIGNALS = (
    SignalDef("keyboard_external", "input", False, "V21/9: H selects the external keyboard on V8", "§2.6.4"),
    SignalDef("v6_cts", "input", True, "V6 pin 5 CTS (pulled high, ignored)", "§2.6.2"),
    SignalDef("v6_dsr", "input", True, "V6 pin 6 DSR (ignored)", "§2.6.2"),
    SignalDef("tel1", "input", False, "TEL 1 (V10 pin 1 = V7 pin 9), passive wire", "§2.6.3"),
    SignalDef("tel2", "input", False, "TEL 2 (V10 pin 2 = V7 pin 10), passive wire", "§2.6.3"),
    SignalDef("tel3", "input", False, "TEL 3 (V10 pin 3 = V7 pin 11), passive wire", "§2.6.3"),
    SignalDef("v6_rts", "output", False, "V6 pin 4 RTS: H during a transfer; the cassette: record", "§2.6.2"),
    SignalDef("v6_dtr", "output", False, "V6 pin 20 DTR: H during a transfer; the cassette: run", "§2.6.2"),
    SignalDef("buzzer", "output", False, "V16/6 buzzer: a pulse per accepted key (P67 = 0)", "§2.4.9"),
    SignalDef("nc_ready", "output", False, "V18/7 NC-Bereitschaft: H about 2 s after power-on", "§2.4.5"),
    SignalDef("data_bus", "output", 0, "V17 data bus: the mode code after a mode change (BA)", "§2.4.1",
              type="int"),
)
