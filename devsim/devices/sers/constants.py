"""Constants of the SERS model: firmware, motor geometry, display priorities (manual §3.5), error bits (§4.8.3.1)."""

from __future__ import annotations

__all__ = [
    "DRIVE_ERRORS",
    "ELECTRICAL_PERIOD",
    "EMCY_CODES",
    "ERROR_DISPLAY",
    "FAULT_MESSAGES",
    "FIRMWARE",
    "INC_PER_REV",
    "INPUT_NAMES",
    "LIMIT",
    "OVERTEMP",
    "SHORT",
    "STANDSTILL",
    "STEP_LOSS",
    "UNDERVOLTAGE",
    "WARNING_DISPLAY",
    "WEIGHTED_KINDS",
    "WEIGHTING_PARAMS",
]

FIRMWARE = 120901
INC_PER_REV = 12800
ELECTRICAL_PERIOD = 256  # increments between phase-zero positions (7.2° on a 1.8° motor)
#: The kinds of parameter whose value follows the weighting (P76, P44, P160; §4.8.4.6).
WEIGHTED_KINDS = ("position", "velocity", "acceleration")
WEIGHTING_PARAMS = (76, 44, 160, 121, 122, 123)
INPUT_NAMES = ("limit_left", "limit_right", "stop", "reference", "service_ext")

# Display characters of the drive errors, in the spec's priority order (§4.7).
ERROR_DISPLAY = ((128, "E"), (2, "8"), (512, "9"), (32, "F"), (8192, "c"), (2048, "A"))
WARNING_DISPLAY = ((2, "8"), (4, "9"), (32, "F"), (128, "H"), (1, "L"), (8, "A"), (64, "A"))

# P11 bits that P11=0 may clear only once their cause is gone (spec G-P11CLEAR).
OVERTEMP, STEP_LOSS, SHORT, UNDERVOLTAGE, STANDSTILL, LIMIT = 2, 32, 128, 512, 2048, 8192
#: The drive errors, P11's bits (§4.8.3, P11), as the reference and the logs name them (``P11 8192``).
DRIVE_ERRORS = {OVERTEMP: "overtemperature", STEP_LOSS: "step monitoring", SHORT: "short circuit",
                UNDERVOLTAGE: "undervoltage", STANDSTILL: "standstill monitoring", 4096: "communication",
                LIMIT: "limit switch"}
#: The message of a drive error (P11 bit) or warning (P12 bit) sent unsolicited with
#: ``spontaneous_fault_messages`` (spec G-FAULTMSG; manual §2.1.4 „Vorwarnung Unterspannung“ …).
FAULT_MESSAGES = ({OVERTEMP: "Fehler Übertemperatur", STEP_LOSS: "Fehler Schrittüberwachung",
                   SHORT: "Kurzschluss Leistungsverstärkerkarte oder Motor", UNDERVOLTAGE: "Fehler Unterspannung",
                   STANDSTILL: "Fehler Regelabweichung", LIMIT: "Fehler Lagegrenzwert"},
                  {2: "Warnung Übertemperatur", 4: "Vorwarnung Unterspannung"})
#: The CiA 301/402 emergency error code of each P11 drive error (an EMCY from a CANopen facade).
EMCY_CODES = {OVERTEMP: 0x4310, STEP_LOSS: 0x8611, SHORT: 0x2320, UNDERVOLTAGE: 0x3220, STANDSTILL: 0x8611,
              LIMIT: 0x7320}

