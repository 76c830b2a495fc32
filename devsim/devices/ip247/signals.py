"""The IP247's digital signals (manual §2.4, §2.5, §2.8, §2.9, §3.1.3; spec ip247.md §4.13): per
axis the inputs of front connector X7 and the power unit's ready signal, the outputs "position
reached", reset and direction; BASP from the bus; the two LEDs."""

from __future__ import annotations

from devsim.core.kit import SignalDef

__all__ = ["SIGNALS"]

SIGNALS: tuple[SignalDef, ...] = (
    *(d for n in (1, 2, 3) for d in (
        SignalDef(f"ANF{n}", "input", False, f"axis {n} limit switch Anfang (24 V = True)", "§2.5"),
        SignalDef(f"END{n}", "input", False, f"axis {n} limit switch Ende (24 V = True)", "§2.5"),
        SignalDef(f"BERO{n}", "input", False, f"axis {n} reference cam (active high)", "§2.5"),
        SignalDef(f"START{n}", "input", False, f"axis {n} external start/stop: 0→1 stops", "§2.8.4"),
        SignalDef(f"BB{n}", "input", True, f"axis {n} power unit ready", "§2.4"),
        SignalDef(f"PE{n}", "output", False, f"axis {n} position reached", "§2.7.7"),
        SignalDef(f"RS{n}", "output", False, f"axis {n} reset to the power unit: high while the axis has no valid "
                  "machine data, a 100 ms pulse after a machine-data input and at a reference run's start",
                  "§2.8.1"),
        SignalDef(f"RP{n}", "output", False, f"axis {n} direction to the power unit (forward: True with the positive "
                  "pulse edge in the machine data, False with the negative), set before "
                  "the first pulse of a move", "§2.4"),
    )),
    SignalDef("BASP", "input", False, "command output disable from the PLC: every axis stops", "§2.9"),
    SignalDef("led_green", "output", True, "module running", "§3.1.3"),
    SignalDef("led_red", "output", False, "an error ≥ 10 is pending", "§3.1.3"),
)
