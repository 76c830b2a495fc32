"""The discrete and analog signals of the POSELESTA, as electrical levels (True = H = 24 V):
the host side (manual §2.3.11, §2.4.5, §2.4.9, §2.6.2, §2.6.3; spec poselesta.md §2.6, §3.10,
§3.11) and the machine interface, inputs V19–V24 and outputs V15–V18 (manual §2.3, §2.4; spec
§4.5, §4.6), with the defaults of a wired, idle machine (spec §4.5)."""

from __future__ import annotations

from devsim.core.kit import SignalDef
from devsim.core.signals import SignalBank

__all__ = ["AXES", "INPUTS", "OUTPUTS", "SIGNALS", "feed_pot", "override"]

AXES = "xyzd"


def _inp(name: str, default: bool, doc: str, section: str) -> SignalDef:
    return SignalDef(name, "input", default, doc, section)


def _out(name: str, doc: str, section: str) -> SignalDef:
    return SignalDef(name, "output", False, doc, section)


INPUTS: tuple[SignalDef, ...] = (
    _inp("nc_stop", True, "V19/1 NC-Stop: L = stop effective (braking ramp, HOLD); not in MANUAL", "§2.3.1"),
    _inp("emergency_stop", True, "V19/2 Not-Stop: L = axes stop at once, loops open; release → MANUAL",
         "§2.3.2"),
    _inp("nc_start", False, "V19/3 NC-Start: the rising edge starts or continues the program (P75)", "§2.3.3"),
    *(_inp(f"limit_{d}_{a}", True, f"V19/{pin} limit switch {sign}{a.upper()}: L = actuated", "§2.3")
      for (d, sign, a, pin) in (("pos", "+", "d", 4), ("pos", "+", "z", 5), ("pos", "+", "y", 6),
                                ("pos", "+", "x", 7), ("neg", "−", "d", 8), ("neg", "−", "z", 9),
                                ("neg", "−", "y", 10), ("neg", "−", "x", 11))),
    *(_inp(f"handwheel_{a}", False, f"V20/{pin} handwheel on {a.upper()}", "§2.3")
      for a, pin in (("d", 1), ("z", 2), ("y", 3), ("x", 4))),
    *(_inp(f"jog_{d}_{a}", False, f"V20/{pin} direction key {sign}{a.upper()}: H = move (MANUAL, PROGRAM_ENTRY)",
           "§2.3.6")
      for (d, sign, a, pin) in (("pos", "+", "d", 5), ("pos", "+", "z", 6), ("pos", "+", "y", 7),
                                ("pos", "+", "x", 8), ("neg", "−", "d", 9), ("neg", "−", "z", 10),
                                ("neg", "−", "y", 11), ("neg", "−", "x", 12))),
    *(_inp(f"jog_step_{n}", False, f"V21/{pin} jogging {n}: a key press moves {n} increments", "§2.3.7")
      for pin, n in enumerate((1, 10, 100, 1000, 10000), start=1)),
    _inp("rapid", False, "V21/6 Eilgang: with a direction key, rapid speed P44–P47", "§2.3.8"),
    _inp("open_loop", False, "V21/7 open loop (switched at standstill only)", "§2.3.9"),
    _inp("key_switch", True, "V21/8 key switch: H = unlocked", "§2.3"),
    _inp("keyboard_external", False, "V21/9: H selects the external keyboard on V8", "§2.6.4"),
    _inp("optional_stop", False, "V21/10: H = M01 stops the program", "§2.3"),
    _inp("block_skip_cancel", False, "V22/1: H = blocks marked / are executed, L = skipped", "§2.3.13"),
    _inp("inch", False, "V22/2: H = programming in inch", "§2.3.14"),
    _inp("axis_enable", True, "V22/3 Achsfreigabe: H = feed released after the travel commands", "§2.3.15"),
    _inp("program_continue", True, "V22/4 Programm fortsetzen: H = next function after position reached",
         "§2.3.16"),
    _inp("tool_change_ack", False, "V22/5 M06 acknowledge: H = tool changed", "§2.3.17"),
    _inp("m10_ack", False, "V22/6 M10 acknowledge: H at output = M10 waits for a negative pulse", "§2.3.18"),
    _inp("mst_ack", False, "V22/7 MST acknowledge (the plant's PLC helper drives it, see config plc)", "§2.3.19"),
    _inp("xy_plotter", False, "V22/8 X/Y plotter (POS III, sampled at power-on)", "§2.3.20"),
    _inp("program_lock_open", True, "V22/9 program lock (POS III): H = open", "§2.3.21"),
    _inp("block_abort", True, "V22/10 Satzabbruch (POS III): H→L aborts the block, continue at N = P90",
         "§2.3.21"),
    SignalDef("feed_pot_v", "input", 10.0, "V23/1 feed potentiometer: 0 … 10 V = 0 … 100 % (MANUAL)", "§2.3.22",
              unit="V", type="float", minimum=0.0, maximum=10.0),
    SignalDef("override_pot_v", "input", 6.667, "V23/4 override potentiometer: 0 … 10 V = 0 … 150 %, "
              "6.667 V = 100 % (automatic modes)", "§2.3.22", unit="V", type="float", minimum=0.0, maximum=10.0),
    *(_inp(f"rm_enable_{a}", True, f"V24/{pin} reference mark activation {a.upper()}", "§2.3.23")
      for pin, a in enumerate(AXES, start=1)),
)

OUTPUTS: tuple[SignalDef, ...] = (
    *(_out(f"m{m:02d}", f"V15/{pin} decoded M{m:02d}", "§2.4.7")
      for pin, m in enumerate((0, 1, 2, 3, 4, 6, 8, 10), start=1)),
    *(_out(f"strobe_{s}", f"V16/{pin} Uebernahme {s.upper()}: the bus carries this function", "§2.4.8")
      for pin, s in enumerate(("m", "s1", "s2", "t", "ba"), start=1)),
    _out("buzzer", "V16/6 buzzer: a pulse per accepted key (P67 = 0)", "§2.4.9"),
    _out("start_stop_status", "V16/8 start/stop status (POS III): H = the 'Start' symbol", "§2.4.10"),
    SignalDef("data_bus", "output", 0, "V17 data bus: two BCD digits of M, S1, S2, T or the mode code (BA)",
              "§2.4.1", type="int"),
    *(_out(f"travel_{a}", f"V18/{pin} Fahrbefehl {a.upper()}: travel command", "§2.4.2")
      for pin, a in enumerate(AXES, start=1)),
    _out("position_reached", "V18/5 Position erreicht (exact positioning)", "§2.4.3"),
    _out("inside_working_field", "V18/6: H = all axes inside the working field (L at power-on)", "§2.4.4"),
    _out("nc_ready", "V18/7 NC-Bereitschaft: H about 2 s after power-on", "§2.4.5"),
    SignalDef("machine_standstill", "output", False, "V18/8 Maschinen-Stillstand: H = all axes at standstill",
              "§2.4.6"),
)

SIGNALS: tuple[SignalDef, ...] = (
    *INPUTS,
    SignalDef("v6_cts", "input", True, "V6 pin 5 CTS (pulled high, ignored)", "§2.6.2"),
    SignalDef("v6_dsr", "input", True, "V6 pin 6 DSR (ignored)", "§2.6.2"),
    SignalDef("tel1", "input", False, "TEL 1 (V10 pin 1 = V7 pin 9), passive wire", "§2.6.3"),
    SignalDef("tel2", "input", False, "TEL 2 (V10 pin 2 = V7 pin 10), passive wire", "§2.6.3"),
    SignalDef("tel3", "input", False, "TEL 3 (V10 pin 3 = V7 pin 11), passive wire", "§2.6.3"),
    *OUTPUTS,
    SignalDef("v6_rts", "output", False, "V6 pin 4 RTS: H during a transfer; the cassette: record", "§2.6.2"),
    SignalDef("v6_dtr", "output", False, "V6 pin 20 DTR: H during a transfer; the cassette: run", "§2.6.2"),
)


def _pot(signals: SignalBank, name: str, full_scale: float) -> float:
    """A potentiometer input (0 … 10 V) in whole percent of ``full_scale`` %, as a factor."""
    return round(max(0.0, min(10.0, float(signals.get(name)))) * full_scale / 10) / 100


def override(signals: SignalBank) -> float:
    """V23/4 (manual §2.3.22): 0 … 10 V = 0 … 150 % (6.667 V = 100 %)."""
    return _pot(signals, "override_pot_v", 150)


def feed_pot(signals: SignalBank) -> float:
    """V23/1 (manual §2.3.22): 0 … 10 V = 0 … 100 %."""
    return _pot(signals, "feed_pot_v", 100)
