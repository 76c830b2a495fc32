"""Configuration of one simulated PCD4 with PCD4.H3 modules (spec pcd4h3.md §1.1, §2.5, §4.1,
§5.4, §9.6; manual §6.4, §7.1.3): the module variant and count, H3DEF.SRC's symbols, the PLC
cycle and its reaction to ComErS, the registers AxInit starts from, and per axis the motor, the
encoder's jumpers and where the limit and reference switches sit (encoder counts from the
position at power-on).
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from devsim.core.points import ascii_digits, ascii_upper
from devsim.core.settings import Check, Keys, Meta, Settings, doc, field
from devsim.core.typed import FieldError
from devsim.devices.pcd4h3.layout import DIAG_FLAGS, DIAG_REGISTERS, FLAGS_PER_AXIS, REGISTERS_PER_AXIS
from devsim.devices.pcd4h3.tables import FLAG_FIELD, REGISTERS, load_registers
from devsim.devices.pcd4h3.units import CHIP_SAMPLE_US

__all__ = ["AXIS", "H3DEF", "JUMPERS", "Pcd4h3Config", "READ_FUNCTIONS", "VARIANTS"]

VARIANTS = ("H310", "H320", "H311", "H321", "H316", "H326", "H317", "H327")
READ_FUNCTIONS = tuple(f.name for f in FLAG_FIELD if f.name.startswith("FRd"))
LOAD_REGISTERS = tuple(r.name for r in load_registers())


def _axis(key: object) -> int:
    text = str(key).removeprefix("axis")
    if not ascii_digits(text) or not 1 <= int(text) <= 32:
        raise ValueError("an axis is 1 … 32 (or axis1 … axis32)")
    return int(text)


def _register(key: object) -> str:
    """A load register's symbol in any case (the PCD assembler ignores case, manual §7.1.5), ASCII:
    str.lower made the Kelvin sign U+212A a k."""
    symbol = {ascii_upper(name): name for name in LOAD_REGISTERS}.get(ascii_upper(str(key)))
    if symbol is None:
        raise ValueError(f"not a load register of an axis block ({', '.join(LOAD_REGISTERS)})")
    return symbol


def _flag(key: object) -> str:
    """A flag's symbol in any case (manual §7.1.5)."""
    symbol = {ascii_upper(f.name): f.name for f in FLAG_FIELD}.get(ascii_upper(str(key)))
    if symbol is None:
        raise ValueError("not a flag of an axis field")
    return symbol


class H3Def(Settings):
    """H3DEF.SRC's installation symbols (manual §7.1.3, spec §4.1)."""

    fmah3: Annotated[int, Meta(ge=0, le=1008), doc(
        "FMAH3: bus address of the first H3 module (modules follow every 16)")] = 0
    imode: Annotated[Literal[5, 6] | None, doc(
        "IMode for AxInit: 6 ±10 V, 5 PWM (default: by the variant); 5 on a ±10 V variant gives an 8-bit "
        "output and the diagnostics warning, 6 on a PWM variant a command error (spec G-26)")] = None
    mna: Annotated[int, Meta(ge=1, le=32), doc("MNA: number of axes with register blocks and flag fields")] = 2
    baf: Annotated[int, Meta(ge=0, le=8191), doc("BAF: first flag of the axis fields")] = 2000
    bar: Annotated[int, Meta(ge=0, le=4095), doc("BAR: first register of the axis blocks")] = 2000
    bac: Annotated[int, Meta(ge=0, le=1599), doc("BAC: the counter the FBs use")] = 1000
    bafb: Annotated[int, Meta(ge=0, le=999), doc("BAFB: first function block number (documentation)")] = 900


class Jumpers(Settings):
    """The encoder jumpers common to both axes (manual §6.4, spec §2.5); the factory setting suits the simulated
    encoder."""

    invert_a: Annotated[bool, doc(
        "A/Ā: phase A inverted (factory Ā); changing A or B alone reverses the count")] = True
    invert_b: Annotated[bool, doc("B/B̄: phase B inverted (factory B̄)")] = True
    index_invert: Annotated[bool, doc(
        "IN/ĪN: index inverted (factory IN); inverted, the decoder sees A = B = IN = 0 at every fourth count and "
        "captures there (the manual's malfunction), also with in_rp: ref on the 24 V types")] = False
    sink_mode: Annotated[bool, doc("Q/S: 24 V encoder inputs in sink mode (signal levels only)")] = False


_Counts = float | None
_Range = tuple[float, float] | None


class Axis(Settings):
    """One axis: motor, encoder, jumpers, switches (spec §2.5, §5.4, §5.9, §5.10); positions in encoder counts
    from where the axis stood at power-on."""

    encoder_lines: Annotated[int, Meta(ge=1, le=1_000_000), doc(
        "encoder lines per revolution (index every 4 × lines counts)")] = 500
    index_offset: Annotated[int, doc("count of the first index mark")] = 0
    kv: Annotated[float, Meta(gt=0, le=1e8), doc("motor with amplifier: counts/s per volt")] = 10_000.0
    tau_ms: Annotated[float, Meta(ge=0, le=10_000), doc("motor time constant τm, ms")] = 20.0
    in_rp: Annotated[Literal["index", "ref"], doc(
        "jumper IN/RP: terminal 4/12 feeds the decoder's index (index) or is only a reference switch (ref; 24 V "
        "types, the 5 V types take the index from the D-Sub)")] = "index"
    pwm_logic: Annotated[Literal["sign_magnitude", "bridge"], doc(
        "PWM output jumper (PWM types): sign and magnitude or H-bridge logic (the output is reported as a signed "
        "duty either way)")] = "sign_magnitude"
    ls1: Annotated[_Counts, doc("limit switch LS1 opens at and below this count (negative end)")] = None
    ls2: Annotated[_Counts, doc("limit switch LS2 opens at and above this count (positive end)")] = None
    ref_switch: Annotated[_Range, doc("reference switch closed on [low, high] counts")] = None
    hard_stops: Annotated[_Range, doc("mechanical end stops [low, high] counts: the motor stops there")] = None


_RegisterSymbol = Literal[tuple(r.name for r in REGISTERS)]  # type: ignore[valid-type]


class Display(Settings):
    """DP14 for one axis (manual §7.4 DP14)."""

    reg1: Annotated[_RegisterSymbol, doc("first value (top line)")] = "RActP"
    reg2: Annotated[_RegisterSymbol, doc("second value (bottom line)")] = "RSetV"


def _blocks_fit(h3def: H3Def) -> H3Def:
    """The axis blocks lie inside the PCD's media: registers R 0 … 4095, flags F 0 … 8191 (manual
    §7.1.3: MNA blocks of NoRfeA registers from BAR and of NoFfeA flags from BAF)."""
    for what, start, size, last in (("BAR", h3def.bar, len(REGISTERS), 4095), ("BAF", h3def.baf, len(FLAG_FIELD), 8191)):
        end = start + h3def.mna * size - 1
        if end > last:
            media = "R" if what == "BAR" else "F"
            raise ValueError(f"{what} {start} with MNA {h3def.mna}: the axis {'blocks' if media == 'R' else 'fields'} "
                             f"{media} {start} … {end} pass {media} {last}")
    return h3def


def _diagnostics_apart(config: Pcd4h3Config) -> None:
    """The simulator's diagnostics block (spec §9.6.3: 16 registers and 8 flags per axis from
    ``diagnostics``) lies apart from the axis blocks and flag fields the library reserves (manual
    §7.1.3, MNA: "Entsprechend dieser Angabe werden die benötigten Speichermedien (Register, Flag)
    reserviert"): over them it would shadow the axes' registers and flags (a read gives the
    diagnostics, a write is refused)."""
    h3def, mna = config.h3def, config.h3def.mna
    register, flag = config.diagnostics
    for media, what, base, size, first, per_axis, (block, verb, axes) in (
        ("R", "BAR", h3def.bar, REGISTERS_PER_AXIS, register, DIAG_REGISTERS, ("block", "overlaps", "blocks")),
        ("F", "BAF", h3def.baf, FLAGS_PER_AXIS, flag, DIAG_FLAGS, ("flags", "overlap", "fields")),
    ):
        end, axes_end = first + mna * per_axis - 1, base + mna * size - 1
        if first <= axes_end and base <= end:
            raise FieldError("diagnostics", f"the diagnostics {block} {media} {first} … {end} {verb} the axis {axes} "
                                            f"{media} {base} … {axes_end} ({what} {base}, MNA {mna}): move it")


#: The nested parts, by their table names.
H3DEF, JUMPERS, AXIS = H3Def, Jumpers, Axis


class Pcd4h3Config(Settings):
    """Configuration of one simulated PCD4 with PCD4.H3 modules (spec pcd4h3.md §9.6)."""

    variant: Annotated[Literal[VARIANTS], doc(  # type: ignore[valid-type]
        "module type: H3ab, a axes, b 0/1 ±10 V, 6/7 PWM (LM629)")] = "H320"
    modules: Annotated[int, Meta(ge=1, le=16), doc("H3 modules plugged from FMAH3 on")] = 1
    station: Annotated[int, Meta(ge=0, le=253), doc("S-Bus station number")] = 1
    firmware: Annotated[str, doc("what S-Bus 'read firmware version' answers (3 characters)")] = "003"
    response_delay_ms: Annotated[float, Meta(ge=0, le=1000), doc(
        "the S-Bus answer leaves this long after the request")] = 2.0
    h3def: Annotated[H3Def, Check(_blocks_fit), doc("H3DEF.SRC symbols")] = field(default_factory=H3Def)
    jumpers: Annotated[Jumpers, doc("the jumpers common to both axes (per axis: in_rp under axes)")] = field(
        default_factory=Jumpers)
    flag_map: Annotated[dict[Any, Annotated[int, Meta(ge=0, le=34)]], Keys(_flag, "flag"), doc(
        "flag offsets replacing the reconstructed ones (G-1), e.g. {FStart: 28}")] = {}
    plc_cycle_ms: Annotated[float, Meta(ge=1, le=1000), doc("PLC cycle: AxHndlg for every axis once per cycle")] = 10.0
    comers_action: Annotated[Literal["continue", "halt", "xob13_diag"], doc(
        "what ComErS does: go on, or halt the PCD (status H) as the manual's commissioning ComErS; xob13_diag "
        "halts and keeps the diagnostics")] = "continue"
    user_program: Annotated[Literal["example1", "example2", "example3"] | None, doc(
        "a user program the PLC runs on axis 1: the manual's Example 1, 2 or 3 (keys on inputs I 0 … 15: use "
        "FMAH3 48)")] = None
    cyclic_reads: Annotated[list[Literal[READ_FUNCTIONS]], doc(  # type: ignore[valid-type]
        "read functions the user program sets every cycle, e.g. [FRdAP, FRdSV] (Examples 2 and 3)")] = []
    emulate_user_limit_stop: Annotated[bool, doc(
        "stop (FStop) an axis whose limit switch opens, as a user program would; the module itself never does")] = False
    display: Annotated[dict[Any, Display], Keys(_axis, "axis"), doc(
        "axes whose PCA2.D14 display the user program drives every cycle")] = {}
    rsigb_bit12_inverted: Annotated[bool, doc(
        "RSigB bit 12 as the manual's text has it (0 = forward), G-5")] = False
    velocity_readback_unsigned: Annotated[bool, doc(
        "FRdAV and FRdSV give the speed without its sign, as the manual's ranges (0 …) read, G-11")] = False
    emulate_host_interrupt: Annotated[bool, doc(
        "RSigB bit 15 is the chip's host interrupt: 1 while a status flag its mask enables (after RESET all "
        "but the breakpoint's) is set, G-12")] = False
    literal_mcw_command: Annotated[bool, doc(
        "FSetPE sends an MCW low byte other than 1Ah/1Bh to the chip as its command byte (hazardous: 00h is "
        "RESET), G-8")] = False
    crc_excludes_fs: Annotated[bool, doc(
        "serial S-Bus: also take a request whose CRC was computed without the leading FS byte (tolerance, spec "
        "§9.2)")] = False
    fb_sample_time_us: Annotated[float, Meta(gt=0, le=10_000), doc(
        "the sample time the FBs' conversion constants assume (manual 22348·10⁻⁶ = 65536 · 341 µs), G-6")] = 341.0
    chip_sample_time_us: Annotated[float, Meta(ge=100, le=2000), doc(
        "the LM628's sample period, 2048 clock periods (6 MHz: 341.333 µs; 8 MHz: 256 µs), §5.1")] = CHIP_SAMPLE_US
    diagnostics: Annotated[tuple[Annotated[int, Meta(ge=0, le=8191)], Annotated[int, Meta(ge=0, le=8191)]], doc(
        "first register and first flag of the simulator's read-only diagnostics block (16 registers and 8 flags "
        "per axis, apart from the axis blocks and fields)")] = (4000, 8000)
    init: Annotated[dict[Any, Annotated[dict[Any, float], Keys(_register, "register")]], Keys(_axis, "axis"), doc(
        "register contents loaded before AxInit at every cold start (MCFac as a number; others integers); unset "
        "registers keep theirs")] = {}
    axes: Annotated[dict[Any, Axis], Keys(_axis, "axis"), doc("per axis: motor, encoder, switches")] = {}

    def __post_init__(self) -> None:
        _diagnostics_apart(self)
