"""GMS96 pure data tables: N parameters, status bytes, markers, messages, faults, variants.

No behaviour lives here, only constants and a few pure helper functions (range clamping,
V-factor, status-byte conversion, name normalisation), so that ``device.py``, the codec and the
tests share one transcription of the manual.

Sources (spec = ``shared/specs/gms96.md``, manual = seed ``001_9e8a165107a15938.txt``; where they
differ the manual wins):

* N parameters ............ spec §4.6, §3.8.10  = manual §2.3.1 "N Standard-Parameter-Eingabe"
* other settable state .... spec §4.7, §3.8    = manual §2.3.1 B, M, S, f, o, G, s
* status bytes ............ spec §4.3.1-§4.3.3 = manual §2.3.1 T (P1=3), §2.3.2 #1
* special markers ......... spec §4.4          = manual §2.4.1 "Spezielle Merker"
* messages / MB5 / faults . spec §4.5          = manual §2.3.1 Q (message 23), §2.4.3, §3.1
* variants ................ spec §4.12.4       = manual §6 "Leistungsdaten"
* V-factor ................ spec §5.2          = manual §2.7

Provenance: values the manual does not give are simulator choices ([R] in the spec); they are
listed in :data:`N_SIMULATOR_DEFAULTS` (N parameters) and marked "[R]" in the ``doc`` strings.

Public names (beyond the agreed API, all documented below): ``N_SIMULATOR_DEFAULTS``,
``N_DUAL_VALUE``, ``N10_STEPPER_RANGE``, ``N50_BITS``, ``INT24_MIN``/``INT24_MAX``,
``decode_reference_type``, ``current_gain_limits``, ``decode_bits``, ``k_from_status``,
``MARKER_ADDRESSES``, ``MARKER_INFO``, ``MARKER_BYTES``, ``SPECIAL_MARKER_BYTES``,
``MARKER_BYTE_COUNT``, ``m_function_marker``, ``MESSAGE_REFERENCE_DISTANCE_LIMIT``,
``MESSAGE_MIN``/``MESSAGE_MAX``, ``FaultDef``, ``Variant``, ``variant``, ``RANGES``,
``clamp_setting``, ``SAVED_SETTINGS``, ``M_COUNTER_INPUT_BELOW``, ``V_FACTOR_TABLE``,
``min_speed``, ``quantize_speed``, ``SAVE_KEY``.
"""

from __future__ import annotations

from collections.abc import Mapping

import msgspec

__all__ = [
    "FIRMWARE_VERSION",
    "POSITION_MIN",
    "POSITION_MAX",
    "INT24_MIN",
    "INT24_MAX",
    "N_TABLE",
    "N_SIMULATOR_DEFAULTS",
    "N_DUAL_VALUE",
    "N10_STEPPER_RANGE",
    "N50_BITS",
    "clamp_n",
    "current_gain_limits",
    "decode_reference_type",
    "STATUS_BITS",
    "MEMORY_STATUS_BITS",
    "K_BITS",
    "decode_bits",
    "k_from_status",
    "MARKERS",
    "MARKER_ADDRESSES",
    "MARKER_INFO",
    "MARKER_BYTES",
    "SPECIAL_MARKER_BYTES",
    "MARKER_BYTE_COUNT",
    "m_function_marker",
    "MESSAGES",
    "MESSAGE_REFERENCE_DISTANCE_LIMIT",
    "MESSAGE_MIN",
    "MESSAGE_MAX",
    "ERROR_BITS",
    "FaultDef",
    "FAULTS",
    "Variant",
    "VARIANTS",
    "DEFAULT_VARIANT",
    "variant",
    "DEFAULTS",
    "RANGES",
    "SAVED_SETTINGS",
    "SAVE_KEY",
    "clamp_setting",
    "M_COUNTER_INPUT_BELOW",
    "V_FACTOR_TABLE",
    "v_factor",
    "min_speed",
    "quantize_speed",
]

# ---------------------------------------------------------------------------------------------
# General constants
# ---------------------------------------------------------------------------------------------

#: Software version x 100, answered by ``T1;0`` (identifier ``V``) [M title, §2.3.1 T].
FIRMWARE_VERSION = 404

#: Commanded position range of ``A``/``O``/``v``/``w``/``+`` (−0x7FFF00 .. 0x7FFFFF) [M §1.3, §2.3.1 A].
POSITION_MIN, POSITION_MAX = -8388352, 8388607

from devsim.devices.gms96.nparams import (  # noqa: E402 - the field range (§2.3)  # noqa: E402
    INT24_MAX,
    INT24_MIN,
    N_DUAL_VALUE,
    N_SIMULATOR_DEFAULTS,
    N_TABLE,
    n_range,
)

#: N10 range with the stepper software (KS4/KS8): corner frequency in kHz [M N10].
N10_STEPPER_RANGE: tuple[int, int] = (10, 500)

#: Documented bits of N50 (value to add). Bits 1 and 2 (default 6) are undocumented [M N50].
N50_BITS: dict[str, int] = {"ACTUAL_FROM_COUNTER_INPUT": 0x01}


def current_gain_limits(index: int, n34: int, n35: int) -> tuple[int, int]:
    """Dynamic range of N34/N35: "P may be lowered to min. 150 % of the I part and vice versa".

    For ``index == 34`` returns ``(ceil(1.5*n35), 32000)``; for ``index == 35`` returns
    ``(0, floor(n34/1.5))`` (the other parameter's current value is the constraint).
    """
    if index == 34:
        return max(0, -(-3 * n35 // 2)), 32000
    if index == 35:
        return 0, max(0, (2 * n34) // 3)
    raise KeyError(index)


def clamp_n(
    index: int,
    value: int,
    current: Mapping[int, int] | None = None,
    *,
    stepper: bool = False,
) -> int:
    """Clamp ``value`` to the range of N parameter ``index`` (spec §3.8.10: out of range -> clamp).

    Raises ``KeyError`` for an undefined index (the device ignores those).  Parameters without a
    documented range are clamped to the 24-bit field.  ``current`` (the card's current N values)
    enables the N34 >= 1.5*N35 coupling; ``stepper=True`` uses :data:`N10_STEPPER_RANGE` for N10.
    """
    p = N_TABLE[index]
    lo, hi = n_range(p)
    if stepper and index == 10:
        lo, hi = N10_STEPPER_RANGE
    if current is not None and index in (34, 35):
        n34 = current.get(34, N_TABLE[34].default)
        n35 = current.get(35, N_TABLE[35].default)
        dlo, dhi = current_gain_limits(index, n34, n35)
        lo, hi = max(lo, dlo), min(hi, dhi)
        if lo > hi:  # inconsistent stored pair: prefer the static range
            lo, hi = (p.minimum or 0), (p.maximum or INT24_MAX)
    return max(lo, min(hi, int(value)))


def decode_reference_type(n19: int) -> tuple[int, int]:
    """Split N19 into (P1, P2) of the ``Q`` command run by ``Q-1`` [M N19]: (LSB, middle byte)."""
    raw = n19 & 0xFFFFFF
    return raw & 0xFF, (raw >> 8) & 0xFF


# ---------------------------------------------------------------------------------------------
# Status bytes (spec §4.3, manual §2.3.1 T P1=3, §2.3.2 #1)
# ---------------------------------------------------------------------------------------------

#: Standard status, identifier byte I of the ``T3;0`` answer [M §2.3.1 T].
STATUS_BITS: dict[str, int] = {
    "ESTOP": 0x01,  # I.0 emergency stop (Notaus) active
    "MOTION": 0x02,  # I.1 motion running (indexer or reference run) or block commands (M1.5)
    "MONITORING": 0x04,  # I.2 monitoring (Überwachung) tripped
    "IDXOFF": 0x08,  # I.3 indexer not ready (following error / state after power-on)
    "BUSY": 0x10,  # I.4 CNC command being executed
    "I2T_ACTIVE": 0x20,  # I.5 I2t limitation active now
    "I2T_LATCHED": 0x40,  # I.6 I2t limitation has been active ("speichernd")
    "MESSAGE": 0x80,  # I.7 message code present in MB4
}

#: Memory status, identifier byte I of the ``T3;4`` answer; bits 3 and 7 undefined (0) [M §2.3.1 T].
MEMORY_STATUS_BITS: dict[str, int] = {
    "PLC_STORAGE_ERROR": 0x01,  # I.0 PLC program storage error (e.g. too long)
    "PLC_NOT_RUNNING": 0x02,  # I.1 PLC not running (error in program or memory)
    "FLASH_ERROR": 0x04,  # I.2 programming/erase error of the FLASH memory
    "CNC_STORAGE_ERROR": 0x10,  # I.4 CNC program storage error
    "NV_ERROR": 0x20,  # I.5 NV memory (power-stage parameters): power stage does not go into control
    "EEPROM_DEFECTIVE": 0x40,  # I.6 parameter memory (EEPROM) defective
}

#: Kurzsatz status byte K of the #1 answer [M §2.3.2]; K.2 unused [R].
K_BITS: dict[str, int] = {
    "I2T": 0x01,  # K.0 I2t flag, latched
    "AE": 0x02,  # K.1 address-field extension: MB4 octet follows
    "ESTOP": 0x08,  # K.3
    "MOTION": 0x10,  # K.4
    "MONITORING": 0x20,  # K.5
    "IDXOFF": 0x40,  # K.6
    "BUSY": 0x80,  # K.7
}


def decode_bits(value: int, table: Mapping[str, int]) -> set[str]:
    """Names of all bits of ``table`` that are set in ``value``."""
    return {name for name, mask in table.items() if value & mask}


def k_from_status(status: int, message_pending: bool) -> int:
    """K byte from the T3;0 status byte I (spec §4.3.3 / Appendix B).

    ``K = ((I & 0x1F) << 3) | I.6 | (0x02 if MB4 != 0)``.  I.5 and I.7 have no K equivalent
    (I.7 is replaced by the AE flag computed at the moment of sending).
    """
    k = ((status & 0x1F) << 3) | ((status >> 6) & 0x01)
    if message_pending:
        k |= K_BITS["AE"]
    return k


# ---------------------------------------------------------------------------------------------
# Special PLC markers MB0..MB29 (spec §4.4, manual §2.4.1)
# ---------------------------------------------------------------------------------------------

#: Named special marker bits -> (byte, bit).
MARKERS: dict[str, tuple[int, int]] = {
    "STOP": (0, 0),  # M0.0 STOP state: decelerate (not abort), continue when cleared
    "ABORT": (0, 1),  # M0.1 abort CNC command / program
    "CNC_PROGRAM": (0, 2),  # M0.2 read: CNC program running; write: start program MB2
    "MOTION_ACTIVE": (0, 3),  # M0.3 motion active
    "ESTOP_OK": (0, 4),  # M0.4 emergency-stop status, 0 = emergency-stop situation
    "POSITION_CONTROL": (0, 5),  # M0.5 position controller active
    "MONITORING_FAULT": (0, 6),  # M0.6 power-stage monitoring, 1 = fault
    "IDXOFF": (0, 7),  # M0.7 indexer not active
    "CNC_PROGRAM_DONE": (1, 0),  # M1.0 CNC program finished successfully
    "I2T": (1, 1),  # M1.1 I2t situation is/was present
    "RDY": (1, 2),  # M1.2 ready = NOT BUSY
    "SYNC_STOP": (1, 3),  # M1.3 synchronisation stop (internal)
    "SPEED_REACHED": (1, 4),  # M1.4 set speed reached
    "BLOCK_MARK": (1, 5),  # M1.5 block marking (shows as motion in I.1/K.4)
    "EXT_BIT0": (1, 6),  # M1.6 (reserved) extended bit 0 to host, e.g. home position
    "EXT_BIT1": (1, 7),  # M1.7 (reserved) extended bit 1 to host
    "MESSAGE_QUERY": (3, 1),  # M3.1 set by `q`, reset by the PLC
    "MOTION_SUPPRESSED": (3, 4),  # M3.4 motion function suppressed (N17)
    "WAIT_IN_POSITION": (3, 5),  # M3.5 waiting for in-position (H2)
    "SPEED_REDUCTION": (3, 6),  # M3.6 reserved for speed reduction (ISO-GB/MS only)
    "SAVE_STATIC_DATA": (3, 7),  # M3.7 save DW0..39 on a monitoring situation
    "MESSAGE_ACK": (13, 6),  # M13.6 error/message acknowledge (Enter key)
    "S_FUNCTION": (15, 7),  # M15.7 M bit of the S function (m100)
    "T_FUNCTION": (18, 7),  # M18.7 M bit of the T function (m101)
}

#: Step5 address ("M0.1") -> name in :data:`MARKERS`.
MARKER_ADDRESSES: dict[str, str] = {f"M{b}.{i}": name for name, (b, i) in MARKERS.items()}

#: name -> (access per manual, meaning). Access: r/w allowed, '.' forbidden, upper case = normal use.
MARKER_INFO: dict[str, tuple[str, str]] = {
    "STOP": ("rw", "STOP state for CNC command/program (Stop-Zustand); 0 = motion enabled"),
    "ABORT": (".w", "abort CNC command or program; a pending STOP is not ended"),
    "CNC_PROGRAM": ("rw", "read: CNC program running; write: start CNC program number MB2"),
    "MOTION_ACTIVE": ("r.", "motion active (Fahrbewegung aktiv)"),
    "ESTOP_OK": ("r.", "emergency-stop status (Status Notaus), 0 = emergency-stop situation"),
    "POSITION_CONTROL": ("r.", "position controller active (Lageregler aktiv)"),
    "MONITORING_FAULT": ("r.", "power-stage monitoring (Endstufen-Überwachung), 1 = fault, stage inactive"),
    "IDXOFF": ("r.", "IDXOFF: 0 = indexer active, 1 = after following error / power-on"),
    "CNC_PROGRAM_DONE": ("r.", "CNC program finished successfully"),
    "I2T": ("r.", "I2t flag (I2t-Merker): I2t situation is/was present"),
    "RDY": ("r.", "RDY = inverted BUSY: 1 = ready"),
    "SYNC_STOP": ("rw", "synchronisation stop (Synchronisations-Stop), used internally"),
    "SPEED_REACHED": ("r.", "set speed reached (Sollgeschwindigkeit erreicht)"),
    "BLOCK_MARK": ("rW", "block marking (Block-Markierung)"),
    "EXT_BIT0": ("r.", "(reserved) extended bit 0 to host (MCC/GSC), e.g. home position (Grundstellung)"),
    "EXT_BIT1": ("r.", "(reserved) extended bit 1 to host (MCC/GSC)"),
    "MESSAGE_QUERY": ("R0", "message query (Meldungs-Abfrage), set by `q`; manual access '[R0]' (sic)"),
    "MOTION_SUPPRESSED": ("r.", "motion function suppressed (Fahr-Funktion unterdrückt, N17)"),
    "WAIT_IN_POSITION": ("r.", "waiting for in-position (Warte auf In-Position, H2)"),
    "SPEED_REDUCTION": ("rW", "reserved for speed reduction (only ISO-GB/MS)"),
    "SAVE_STATIC_DATA": ("rW", "save static data area DW0..39 on a monitoring situation"),
    "MESSAGE_ACK": ("r.", "error/message acknowledge (Fehler-/Meldungs-Quittung, usually Enter key)"),
    "S_FUNCTION": ("Rw", "M bit of the S function (m100)"),
    "T_FUNCTION": ("Rw", "M bit of the T function (m101)"),
}

#: Named special marker bytes -> byte number (MW16 = MB16 high byte, MB17 low byte [R Step5]).
MARKER_BYTES: dict[str, int] = {
    "PROGRAM_NUMBER": 2,  # MB2 CNC program number to start / started
    "MESSAGE": 4,  # MB4 message code (Meldungs-Code)
    "ERROR_REGISTER": 5,  # MB5 error register (Fehler-Register)
    "M_FUNCTION_FIRST": 6,  # MB6..MB10 M bits M50..M89
    "M_FUNCTION_LAST": 10,
    "M_DATUM": 11,  # MB11 extended M datum (m P2)
    "OPERATING_MODE": 12,  # MB12 operating-mode register
    "KEYBOARD": 13,  # MB13 keyboard input from the host device
    "S_DATUM": 15,  # MB15 extended S datum (spindle number - 1 in bits 0..6), bit 7 = S function
    "SPINDLE_SPEED_HIGH": 16,  # MW16 high byte (m100 P3)
    "SPINDLE_SPEED_LOW": 17,  # MW16 low byte
    "TOOL_NUMBER": 18,  # MB18 tool number (bits 0..6, non-volatile), bit 7 = T function
    "D_NUMBER": 19,  # MB19 current tool offset memory (m101 P3)
}

#: MB0..MB29 are coupling markers (MB20..29 kept free); MB30..MB255 free PLC markers.
SPECIAL_MARKER_BYTES = range(0, 30)
MARKER_BYTE_COUNT = 256


def m_function_marker(n: int) -> tuple[int, int]:
    """(byte, bit) of the marker for M-function ``n`` (50..89): M50 = M6.0 ... M89 = M10.7."""
    if not 50 <= n <= 89:
        raise ValueError(f"M-function {n} outside 50..89")
    k = n - 50
    return 6 + k // 8, k % 8


# ---------------------------------------------------------------------------------------------
# Messages MB4, error register MB5, fault states (spec §4.5, manual §2.3.1 Q, §2.4.3, §3.1)
# ---------------------------------------------------------------------------------------------

MESSAGE_REFERENCE_DISTANCE_LIMIT = 23

#: Firmware message codes of MB4. Only 23 is documented; every other code 1..255 is application
#: (PLC/SNDM/scenario) defined. 0 = no message.
MESSAGES: dict[int, str] = {
    MESSAGE_REFERENCE_DISTANCE_LIMIT: (
        "reference-run distance limit P3 exceeded with Q P2.6 = 1 (Wegbegrenzung der Referenzfahrt); "
        "the run is stopped and the indexer stays active if it was active before"
    ),
}
MESSAGE_MIN, MESSAGE_MAX = 1, 255

#: MB5 error register bits. Neither the manual nor the spec defines any bit: MB5 ("Fehler-Register,
#: nur in speziellen Steuerungen") is an opaque application byte written by ``SNDF`` (buffered) or
#: the PLC and read with ``T1;3;5``. Kept as an (intentionally empty) table.
ERROR_BITS: dict[int, str] = {}


class FaultDef(msgspec.Struct, frozen=True):
    """One fault state of spec §4.5.3 (plus the reference distance limit of §3.8.14).

    ``status``/``k``/``memory`` name bits in :data:`STATUS_BITS`/:data:`K_BITS`/
    :data:`MEMORY_STATUS_BITS` that are 1 while the fault is present; ``markers`` are
    (name in :data:`MARKERS`, value while faulted); ``inputs`` are input-image bits set to 1;
    ``message`` is the MB4 code raised (or ``None``).
    """

    name: str
    german: str
    sets: str
    effect: str
    clears: str
    status: frozenset[str] = msgspec.field(default_factory=frozenset)
    k: frozenset[str] = msgspec.field(default_factory=frozenset)
    memory: frozenset[str] = msgspec.field(default_factory=frozenset)
    markers: tuple[tuple[str, int], ...] = ()
    inputs: tuple[str, ...] = ()
    message: int | None = None
    blocks_motion: bool = False
    source: str = ""


def _fs(*names: str) -> frozenset[str]:
    return frozenset(names)


FAULTS: dict[str, FaultDef] = {
    f.name: f
    for f in (
        FaultDef(
            "ESTOP",
            "Notaus",
            sets="emergency-stop input at 0 V (low-active)",
            effect="power stage off, motion aborted, queue flushed, CNC program aborted, brake engaged",
            clears="input back to 24 V -> card reset (power-on sequence, IDXOFF = 1) [M: Notaus acts as reset]",
            status=_fs("ESTOP"),
            k=_fs("ESTOP"),
            markers=(("ESTOP_OK", 0),),
            blocks_motion=True,
            source="M §1, §4.2; spec §4.5.3",
        ),
        FaultDef(
            "FOLLOWING_ERROR",
            "Schleppfehler",
            sets="|following error| > N20",
            effect="indexer off (IDXOFF = 1), position controller off, motion aborted, queue flushed, "
            "brake engaged if N21 = 1",
            clears="any successful reference run Q, or Q3 (re-activation of the position controller)",
            status=_fs("IDXOFF"),
            k=_fs("IDXOFF"),
            markers=(("IDXOFF", 1), ("POSITION_CONTROL", 0)),
            blocks_motion=True,
            source="M §2.3.1 N20, T3; spec §4.5.3",
        ),
        FaultDef(
            "MONITORING",
            "Überwachung",
            sets="DC-bus under/overvoltage, short circuit, heat-sink over-temperature, resolver signal "
            "loss; KD/HD also ballast overload, motor over-temperature, DC-bus failure, missing mains "
            "phase, power-module fault, 24 V power fail",
            effect="position and current control off, brake output active (0 V) if programmed, IDXOFF = 1 [R]",
            clears="cause removed and Q3 [R] (config monitoring_reset: q3 | restart)",
            status=_fs("MONITORING", "IDXOFF"),
            k=_fs("MONITORING", "IDXOFF"),
            markers=(("MONITORING_FAULT", 1), ("IDXOFF", 1), ("POSITION_CONTROL", 0)),
            blocks_motion=True,
            source="M §3.1; spec §4.5.3",
        ),
        FaultDef(
            "I2T",
            "I2t-Begrenzung",
            sets="current above the N15 level for too long (2 s at 100 % overload)",
            effect="motor current limited to the N15 level (usually leads to a following error)",
            clears="I2T_ACTIVE clears when the I2t integral is back to 0; the latch (I.6/K.0/M1.1) is "
            "cleared by restart or successful Q [R]",
            status=_fs("I2T_ACTIVE", "I2T_LATCHED"),
            k=_fs("I2T"),
            markers=(("I2T", 1),),
            source="M §3.1, N15; spec §4.5.3, §5.7",
        ),
        FaultDef(
            "RESOLVER_FAILURE",
            "Ausfall Resolver",
            sets="resolver signal loss (resolver variants only)",
            effect="monitoring fault (see MONITORING)",
            clears="as MONITORING",
            status=_fs("MONITORING", "IDXOFF"),
            k=_fs("MONITORING", "IDXOFF"),
            markers=(("MONITORING_FAULT", 1), ("IDXOFF", 1), ("POSITION_CONTROL", 0)),
            inputs=("E2.3",),
            blocks_motion=True,
            source="M §2.4.2, §3.1; spec §4.5.3",
        ),
        FaultDef(
            "OUTPUT_SHORT_CIRCUIT",
            "Kurzschluss 24V",
            sets="24 V outputs short circuit / overload, total output current about 2.5 A",
            effect="all outputs switched off",
            clears="switch the 24 V supply off for >= 10 s and remove the cause",
            inputs=("E2.2",),
            source="M §2.4.2, §4.2; spec §4.5.3",
        ),
        FaultDef(
            "NV_PARAMETER_ERROR",
            "Fehler NV-Speicher (Endstufen-Parameter)",
            sets="checksum error of the NV power-stage parameters at start",
            effect="power stage does not go into control",
            clears="reprogram + s85;170 [R]",
            memory=_fs("NV_ERROR"),
            blocks_motion=True,
            source="M §2.3.1 T3;4; spec §4.5.3, §4.1.2",
        ),
        FaultDef(
            "EEPROM_DEFECTIVE",
            "Parameterspeicher (E2PROM) defekt",
            sets="EEPROM checksum error at start",
            effect="parameter memory reported defective; defaults used [R]",
            clears="reprogram + s85;170 [R]",
            memory=_fs("EEPROM_DEFECTIVE"),
            source="M §2.3.1 T3;4; spec §4.5.3, §4.1.2",
        ),
        FaultDef(
            "PLC_PROGRAM_ERROR",
            "PLC-Programm-Speicherungsfehler / PLC läuft nicht",
            sets="PLC program storage error (e.g. too long) or error in program/memory",
            effect="PLC not running",
            clears="successful PLC download and start [R]",
            memory=_fs("PLC_STORAGE_ERROR", "PLC_NOT_RUNNING"),
            source="M §2.3.1 T3;4; spec §4.5.3",
        ),
        FaultDef(
            "FLASH_ERROR",
            "Programmier-/Löschfehler des Flash-Speichers",
            sets="FLASH programming/erase error (e.g. after a download)",
            effect="download failed, the FLASH stays as it was (fault flash_error)",
            clears="successful download or power-on [R]",
            memory=_fs("FLASH_ERROR"),
            source="M §2.3.1 T3;4; spec §4.5.3",
        ),
        FaultDef(
            "CNC_STORAGE_ERROR",
            "CNC-Programm-Speicherungsfehler",
            sets="CNC program storage error, e.g. program memory full [R]",
            effect="program rejected",
            clears="successful download or power-on [R]",
            memory=_fs("CNC_STORAGE_ERROR"),
            source="M §2.3.1 T3;4; spec §4.5.3",
        ),
        FaultDef(
            "REFERENCE_DISTANCE_LIMIT",
            "Wegbegrenzung der Referenzfahrt",
            sets="reference run travelled further than Q P3 (> 0)",
            effect="run stopped; P2.6 = 0: reference run failed, IDXOFF = 1; P2.6 = 1: message 23, "
            "indexer stays active if it was active before",
            clears="successful reference run; message 23 cleared by transmission in the #1 answer",
            status=_fs("MESSAGE"),
            k=_fs("AE"),
            message=MESSAGE_REFERENCE_DISTANCE_LIMIT,
            source="M §2.3.1 Q P2.6/P3; spec §3.8.14, §5.6 (not in the §4.5.3 table)",
        ),
    )
}


from devsim.devices.gms96.variants import DEFAULT_VARIANT, VARIANTS, Variant, variant  # noqa: E402

# ---------------------------------------------------------------------------------------------
# Other settable state and defaults (spec §3.8, §4.7, manual §2.3.1)
# ---------------------------------------------------------------------------------------------

#: "Grundstellung" restored by ``r`` (P3=0) and power-on values of state that is not an N parameter.
#: ``f`` = M after reset [R]; override_active 1 [R]; override_inactive_value 100 [R]; G90 [R], G94 [M].
DEFAULTS: dict[str, int] = {
    "M": 2000,  # rapid / max speed [Hz]
    "B": 50,  # acceleration [Hz/ms]
    "S": 100,  # reference search speed [Hz]
    "f": 2000,  # working speed [Hz] (= M, G0 state)
    "f_fraction": 0,  # f P2, 1/256 inc/rev (G95)
    "override_active": 1,  # o1
    "override_inactive_value": 100,  # o2;P2 [%]
    "override_pot": 100,  # potentiometer override [%] (scenario)
    "coordinates": 90,  # G90 absolute
    "feed_mode": 94,  # G94 inc/s
    "zero_offset": 53,  # G53 = no zero offset selected
    "spindle_speed": 0,  # #8 value
    "analog_out": 0,  # p12 / AB2
}

#: Ranges of commands/settings (inclusive). "f" upper bound is the current M value (f > M -> M).
RANGES: dict[str, tuple[int, int]] = {
    "M": (5, 2_000_000),  # plus 0/1 = counter-input mode (see M_COUNTER_INPUT_BELOW)
    "B": (1, 30_000),
    "S": (20, 5_000),
    "f": (1, 2_000_000),
    "f_fraction": (0, 255),
    "override_inactive_value": (0, 100),  # o2;P2
    "external_override": (0, 125),  # #9
    "override_pot": (0, 125),
    "spindle_speed": (0, 65_535),  # #8
    "analog_out": (0, 255),  # p12
    "torque_abort": (0, 100),  # H7;P2 [%]
    "register": (0, 19),  # c P2
    "data_offset": (0, 254),  # d P2
    "position": (POSITION_MIN, POSITION_MAX),
    "q8_speed": (0, 0x3EFFFF),  # Q8 P3 (>= 0x3F0000: pulse-derived speed)
    "message": (0, 255),
}

#: Settings stored in EEPROM by ``s85;170`` besides all N parameters [M §2.3.1 s].
SAVED_SETTINGS: frozenset[str] = frozenset({"M", "S", "B", "override_active"})

#: Safety key of the ``s`` command (P1, P2).
SAVE_KEY: tuple[int, int] = (85, 170)

#: An M value below this (0 or 1) selects the quadrature counter input after s85;170 + restart [M §2.6].
M_COUNTER_INPUT_BELOW = 2


def clamp_setting(name: str, value: int) -> int:
    """Clamp ``value`` to :data:`RANGES` ``name``; M values 0/1 (counter-input mode) are kept."""
    if name == "M" and 0 <= value < M_COUNTER_INPUT_BELOW:
        return int(value)
    lo, hi = RANGES[name]
    return max(lo, min(hi, int(value)))


# ---------------------------------------------------------------------------------------------
# V-factor (spec §5.2, manual §2.7)
# ---------------------------------------------------------------------------------------------

#: (highest M value of the band, V-factor). Internally speeds are held in 1..50000 only.
V_FACTOR_TABLE: tuple[tuple[int, int], ...] = (
    (50_000, 1),
    (100_000, 2),
    (200_000, 4),
    (400_000, 8),
    (500_000, 10),
    (1_000_000, 20),
    (1_250_000, 25),
    (2_000_000, 40),
)


def v_factor(m_value: int) -> int:
    """Speed resolution (V-factor) the card derives from the M value (manual §2.7 table).

    Values below the table (M 0..4, incl. counter-input mode) give 1; above 2000000 (clamped
    anyway) give 40.
    """
    for upper, v in V_FACTOR_TABLE:
        if m_value <= upper:
            return v
    return V_FACTOR_TABLE[-1][1]


def min_speed(m_value: int) -> int:
    """Minimum useful ``f`` speed in G94 = 2 x V-factor [M §2.7]."""
    return 2 * v_factor(m_value)


def quantize_speed(speed: int, m_value: int) -> int:
    """Effective speed [R §5.2]: V * floor(speed / V); 0 means the move stalls."""
    v = v_factor(m_value)
    return v * (int(speed) // v)
