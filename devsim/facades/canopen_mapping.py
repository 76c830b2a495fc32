"""The checks a node makes on the PDO parameters a master writes.  The transmission type
(sub-index 02h of 1400h … / 1800h …, CiA 301 §7.5.2.35): 241 … 251 are reserved and 252/253 need
remote frames the node does not serve, so they are aborted 0609 0030h.  The COB-ID (sub-index
01h, CiA 301 §7.5.2.35/§7.5.2.37) that makes the PDO valid (bit 31 = 0) is aborted 0609 0030h
with an 11-bit CAN-ID CiA 301 §7.3.5 restricts (:data:`RESTRICTED_CAN_IDS`, as for 1005h), and
when it would change bits 0 … 29 of a PDO that is valid (the way to another CAN-ID is to make the
PDO not valid first); a COB-ID with bit 31 = 1 uses no CAN-ID and is taken (80000000h switches a
PDO off, as CANopenNode takes it).  The mapping
(CiA 301 §7.5.2.36, RPDO mapping parameter 1600h …, and §7.5.2.38, TPDO mapping parameter 1A00h …:
the re-mapping procedure).
A mapping entry (sub-index 01h … 08h) that names an object the dictionary does not have (or a
sub-index it does not have; a VAR has 00h alone) is aborted 0602 0000h; one naming an object that cannot be mapped (PDOMapping=0 in the EDS, a length
other than the object's, into an RPDO an object that cannot be written, into a TPDO one that
cannot be read) 0604 0041h; enabling the mapping (sub-index 00h = the number of entries) with
more than 8 entries or more than the PDO's 64 bits 0604 0042h.  An entry of 0 (cleared) is
taken.  The node calls :func:`check` before it stores the value, so nothing refused is kept.
The COB-ID SYNC (1005h, CiA 301 §7.5.2.5) the node takes is :func:`sync_cob_id`'s."""

from __future__ import annotations

from typing import Any

from canopen.objectdictionary import ODVariable
from canopen.sdo.exceptions import SdoAbortedError

__all__ = ["CANNOT_BE_MAPPED", "ENTRIES", "NOT_IN_OD", "TOO_LONG", "VALUE_RANGE_EXCEEDED", "check", "is_pdo_parameter",
           "sync_cob_id"]

NOT_IN_OD = 0x06020000  # object does not exist in the object dictionary
CANNOT_BE_MAPPED = 0x06040041  # object cannot be mapped to the PDO
TOO_LONG = 0x06040042  # the number and length of the objects to be mapped would exceed PDO length
ENTRIES = 8  # mapping entries per PDO (the EDS's sub-indices 01h … 08h)
VALUE_RANGE_EXCEEDED = 0x06090030
PDO_BITS = 64
#: The transmission types a PDO's sub-index 02h takes (an RPDO is taken as it arrives; a TPDO goes
#: out at SYNCs, type 0 after a change, 1 … 240 every that many, or on events, 254 and 255).
TRANSMISSION_TYPES = frozenset((*range(241), 254, 255))


def is_pdo_parameter(index: int) -> bool:
    """A PDO communication (1400h … 15FFh, 1800h … 19FFh) or mapping (1600h … 17FFh, 1A00h …
    1BFFh) parameter."""
    return 0x1400 <= index <= 0x1BFF


def check(node: Any, index: int, subindex: int, data: bytes) -> None:
    """Raise the CiA 301 abort for writing ``data`` into sub-index ``subindex`` of PDO parameter
    ``index`` of ``node`` (a canopen local node), if the write is one to refuse."""
    if index & 0x0200 == 0:  # communication parameter
        if subindex == 1:
            _check_cob_id(node, index, _unsigned32(data))
        if subindex == 2 and data and data[0] not in TRANSMISSION_TYPES:
            raise SdoAbortedError(VALUE_RANGE_EXCEEDED)
        return
    if subindex == 0:
        count = data[0] if data else 0
        if count > ENTRIES:
            raise SdoAbortedError(TOO_LONG)
        bits = sum(_entry(node, index, sub)[2] for sub in range(1, count + 1))
        if bits > PDO_BITS:
            raise SdoAbortedError(TOO_LONG)
        return
    entry = _unsigned32(data)
    if entry == 0:
        return
    target, sub, bits = _fields(entry)
    variable = _variable(node.object_dictionary, target, sub)
    receive = index < 0x1800
    if (not getattr(variable, "pdo_mappable", False) or bits != len(variable)
            or not (variable.writable if receive else variable.readable)):
        raise SdoAbortedError(CANNOT_BE_MAPPED)


def _check_cob_id(node: Any, index: int, cob_id: int) -> None:
    """A PDO's COB-ID: valid with a restricted CAN-ID, or another CAN-ID while the PDO is valid,
    is aborted 0609 0030h."""
    if cob_id & PDO_NOT_VALID:
        return
    stored = _unsigned32(node.get_data(index, 1))
    if _restricted(cob_id) or (not stored & PDO_NOT_VALID and (stored ^ cob_id) & PDO_CAN_ID_BITS):
        raise SdoAbortedError(VALUE_RANGE_EXCEEDED)


def _unsigned32(data: bytes) -> int:
    """An UNSIGNED32 as CANopen sends it (little-endian; a shorter download padded with zeros)."""
    return int.from_bytes(data[:4].ljust(4, b"\0"), "little")


def _entry(node: Any, index: int, subindex: int) -> tuple[int, int, int]:
    return _fields(_unsigned32(node.get_data(index, subindex)))


def _fields(entry: int) -> tuple[int, int, int]:
    """A mapping entry's object index, sub-index and length in bits (CiA 301 §7.5.2.36)."""
    return entry >> 16, entry >> 8 & 0xFF, entry & 0xFF


def _variable(od: Any, index: int, subindex: int) -> ODVariable:
    if index not in od:
        raise SdoAbortedError(NOT_IN_OD)
    entry = od[index]
    if isinstance(entry, ODVariable) and not subindex:
        return entry
    if isinstance(entry, ODVariable) or subindex not in entry:  # (a VAR is its sub-index 00h alone)
        raise SdoAbortedError(NOT_IN_OD)
    return entry[subindex]


#: The CAN-IDs CiA 301 §7.3.5 restricts (NMT, the reserved ones, the default SDOs, the
#: NMT error control; first, last): no communication object may use them.
RESTRICTED_CAN_IDS = ((0x000, 0x07F), (0x101, 0x180), (0x581, 0x5FF), (0x601, 0x67F), (0x6E0, 0x6FF),
                      (0x701, 0x77F), (0x780, 0x7FF))
SYNC_GEN, FRAME_29_BIT = 1 << 30, 1 << 29
PDO_NOT_VALID, PDO_CAN_ID_BITS = 1 << 31, (1 << 30) - 1  # (a PDO COB-ID's bit 31, and bits 0 … 29)


def _restricted(cob_id: int) -> bool:
    """A COB-ID with an 11-bit frame (bit 29 = 0) whose CAN-ID (bits 10 … 0) CiA 301 §7.3.5 restricts."""
    return not cob_id & FRAME_29_BIT and any(a <= cob_id & 0x7FF <= b for a, b in RESTRICTED_CAN_IDS)


def sync_cob_id(data: bytes) -> int:
    """The CAN-ID of the SYNC a node consumes after a master wrote ``data`` into 1005h (CiA 301
    §7.5.2.5: bit 31 "do not care", bit 30 gen, bit 29 frame, bits 10 … 0 the 11-bit CAN-ID), or
    the abort 0609 0030h: the node generates no SYNC (gen = 1), takes no 29-bit frame (frame = 1,
    or bits 28 … 11 set), and no restricted CAN-ID."""
    value = _unsigned32(data)
    can_id = value & 0x1FFF_FFFF
    if value & (SYNC_GEN | FRAME_29_BIT) or can_id > 0x7FF or _restricted(can_id):
        raise SdoAbortedError(VALUE_RANGE_EXCEEDED)
    return can_id
