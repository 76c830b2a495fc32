"""Configuration of one simulated PCD4 with PCD4.H3 modules (spec pcd4h3.md §1.1, §2.5, §4.1,
§5.4, §9.6; manual §6.4, §7.1.3): the module variant and count, H3DEF.SRC's symbols, the PLC
cycle and its reaction to ComErS, the registers AxInit starts from, and per axis the motor, the
encoder's jumpers and where the limit and reference switches sit (encoder counts from the
position at power-on).
"""

from __future__ import annotations

from devsim.core.settings import (
    Bool,
    DictOf,
    Float,
    Int,
    ListOf,
    Maybe,
    OneOf,
    PairOf,
    Section,
    Setting,
    Text,
)
from devsim.devices.pcd4h3.layout import FLAGS, REGISTERS

__all__ = ["AXIS", "H3DEF", "JUMPERS", "Pcd4h3Config", "READ_FUNCTIONS", "VARIANTS"]

VARIANTS = ("H310", "H320", "H311", "H321", "H316", "H326", "H317", "H327")
READ_FUNCTIONS = tuple(f.symbol for f in FLAGS if f.symbol.startswith("FRd"))
LOAD_REGISTERS = tuple(r.symbol for r in REGISTERS if r.load)


def _axis(key: object) -> int:
    text = str(key).removeprefix("axis")
    number = int(text)
    if not 1 <= number <= 32:
        raise ValueError("an axis is 1 … 32 (or axis1 … axis32)")
    return number


def _register(key: object) -> str:
    if key not in LOAD_REGISTERS:
        raise ValueError(f"not a load register of an axis block ({', '.join(LOAD_REGISTERS)})")
    return str(key)


def _flag(key: object) -> str:
    if key not in {f.symbol for f in FLAGS}:
        raise ValueError("not a flag of an axis field")
    return str(key)


H3DEF = Section("H3DEF.SRC's installation symbols (manual §7.1.3, spec §4.1).", (
    Setting("fmah3", Int(ge=0, le=1008), 0, "FMAH3: bus address of the first H3 module (modules follow every 16)"),
    Setting("imode", Maybe(OneOf(5, 6)), None, "IMode for AxInit: 6 ±10 V, 5 PWM (default: by the variant)"),
    Setting("mna", Int(ge=1, le=32), 2, "MNA: number of axes with register blocks and flag fields"),
    Setting("baf", Int(ge=0, le=8191), 2000, "BAF: first flag of the axis fields"),
    Setting("bar", Int(ge=0, le=4095), 2000, "BAR: first register of the axis blocks"),
    Setting("bac", Int(ge=0, le=1599), 1000, "BAC: the counter the FBs use"),
    Setting("bafb", Int(ge=0, le=999), 900, "BAFB: first function block number (documentation)"),
))

JUMPERS = Section("The encoder jumpers common to both axes (manual §6.4, spec §2.5); the factory setting suits "
                   "the simulated encoder.", (
    Setting("invert_a", Bool(), True, "A/Ā: phase A inverted (factory Ā); changing A or B alone reverses the count"),
    Setting("invert_b", Bool(), True, "B/B̄: phase B inverted (factory B̄)"),
    Setting("index_invert", Bool(), False, "IN/ĪN: index inverted (factory IN); inverted, the decoder sees A = B = "
            "IN = 0 at every fourth count and captures there (the manual's malfunction)"),
    Setting("sink_mode", Bool(), False, "Q/S: 24 V encoder inputs in sink mode (signal levels only)"),
))

AXIS = Section("One axis: motor, encoder, jumpers, switches (spec §2.5, §5.4, §5.9, §5.10); positions in "
               "encoder counts from where the axis stood at power-on.", (
    Setting("encoder_lines", Int(ge=1, le=1_000_000), 500, "encoder lines per revolution (index every 4 × lines counts)"),
    Setting("index_offset", Int(), 0, "count of the first index mark"),
    Setting("kv", Float(gt=0, le=1e8), 10_000.0, "motor with amplifier: counts/s per volt"),
    Setting("tau_ms", Float(ge=0, le=10_000), 20.0, "motor time constant τm, ms"),
    Setting("in_rp", OneOf("index", "ref"), "index", "jumper IN/RP: terminal 4/12 feeds the decoder's index (index) "
            "or is only a reference switch (ref; 24 V types, the 5 V types take the index from the D-Sub)"),
    Setting("pwm_logic", OneOf("sign_magnitude", "bridge"), "sign_magnitude", "PWM output jumper (PWM types): sign "
            "and magnitude or H-bridge logic (the output is reported as a signed duty either way)"),
    Setting("ls1", Maybe(Float()), None, "limit switch LS1 opens at and below this count (negative end)"),
    Setting("ls2", Maybe(Float()), None, "limit switch LS2 opens at and above this count (positive end)"),
    Setting("ref_switch", Maybe(PairOf(Float())), None, "reference switch closed on [low, high] counts"),
    Setting("hard_stops", Maybe(PairOf(Float())), None, "mechanical end stops [low, high] counts: the motor stops there"),
))

Pcd4h3Config = Section("Configuration of one simulated PCD4 with PCD4.H3 modules (spec pcd4h3.md §9.6).", (
    Setting("variant", OneOf(*VARIANTS), "H320", "module type: H3ab, a axes, b 0/1 ±10 V, 6/7 PWM (LM629)"),
    Setting("modules", Int(ge=1, le=16), 1, "H3 modules plugged from FMAH3 on"),
    Setting("station", Int(ge=0, le=253), 1, "S-Bus station number"),
    Setting("firmware", Text(), "003", "what S-Bus 'read firmware version' answers (3 characters)"),
    Setting("response_delay_ms", Float(ge=0, le=1000), 2.0, "the S-Bus answer leaves this long after the request"),
    Setting("h3def", H3DEF, {}, "H3DEF.SRC symbols"),
    Setting("jumpers", JUMPERS, {}, "the jumpers common to both axes (per axis: in_rp under axes)"),
    Setting("flag_map", DictOf(_flag, Int(ge=0, le=34), "flag"), {}, "flag offsets replacing the reconstructed ones "
            "(G-1), e.g. {FStart: 28}"),
    Setting("plc_cycle_ms", Float(ge=1, le=1000), 10.0, "PLC cycle: AxHndlg for every axis once per cycle"),
    Setting("comers_action", OneOf("continue", "halt", "xob13_diag"), "continue", "what ComErS does: go on, or halt "
            "the PCD (status H) as the manual's commissioning ComErS; xob13_diag halts and keeps the diagnostics"),
    Setting("user_program", Maybe(OneOf("example1", "example2", "example3")), None, "a user program the PLC runs "
            "on axis 1: the manual's Example 1, 2 or 3 (keys on inputs I 0 … 15: use FMAH3 48)"),
    Setting("cyclic_reads", ListOf(OneOf(*READ_FUNCTIONS)), [], "read functions the user program sets every cycle, "
            "e.g. [FRdAP, FRdSV] (Examples 2 and 3)"),
    Setting("emulate_user_limit_stop", Bool(), False, "stop (FStop) an axis whose limit switch opens, as a user "
            "program would; the module itself never does"),
    Setting("display", DictOf(_axis, Section("DP14 for one axis (manual §7.4 DP14).", (
        Setting("reg1", OneOf(*(r.symbol for r in REGISTERS)), "RActP", "first value (top line)"),
        Setting("reg2", OneOf(*(r.symbol for r in REGISTERS)), "RSetV", "second value (bottom line)"),
    )), "axis"), {}, "axes whose PCA2.D14 display the user program drives every cycle"),
    Setting("rsigb_bit12_inverted", Bool(), False, "RSigB bit 12 as the manual's text has it (0 = forward), G-5"),
    Setting("diagnostics", PairOf(Int(ge=0, le=8191)), [4000, 8000], "first register and first flag of the "
            "simulator's read-only diagnostics block"),
    Setting("init", DictOf(_axis, DictOf(_register, Float(), "register"), "axis"), {}, "register contents loaded "
            "before AxInit at every cold start (MCFac as a number; others integers); unset registers keep theirs"),
    Setting("axes", DictOf(_axis, AXIS, "axis"), {}, "per axis: motor, encoder, switches"),
))
