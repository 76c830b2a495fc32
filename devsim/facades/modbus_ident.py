"""Read Device Identification (Modbus Application Protocol Specification V1.1b3 §6.21, function
43 / MEI type 14, ``2B 0E``): the device's identification objects and the responses that carry
them.  The request's checks (its length, the Read Device ID code, an unknown object with code 04)
are :mod:`devsim.facades.modbus_pdu`'s, with the other functions' exception responses.

§6.21 models the identification as objects with an id each: the basic ones, all mandatory
(00 VendorName, 01 ProductCode, 02 MajorMinorRevision), the regular ones, optional (03 VendorUrl,
04 ProductName, 05 ModelName, 06 UserApplicationName), and private ones (80h … FFh, extended).
The facade answers as a twin of the simulated device ([DECISION], docs/facades/modbus.md):
VendorName ``devsim`` (the Modbus interface is devsim's: the legacy devices never spoke Modbus, and
the GMS96's manual names no maker; the CANopen facade's identity says ``devsim`` too), ProductCode
the kind (``sers``), MajorMinorRevision devsim's version, ProductName the kind's description,
UserApplicationName the device's name in the run or plant.  devsim has no URL and no model name
besides these: 03 and 05 are not given, and no private objects: conformity level 82h (regular
identification, stream and individual access).  The objects are ASCII strings (§6.21's table):
German letters are written out (``Stögra`` → ``Stoegra``), other letters lose their accents.
"""

from __future__ import annotations

import unicodedata
from collections.abc import Mapping

__all__ = ["BASIC", "CODES", "CONFORMITY", "EXTENDED", "READ_DEVICE_ID", "REGULAR", "SPECIFIC", "identification",
           "individual", "stream"]

#: §6.19: the MEI type of Read Device Identification (13, 0Dh, is the CANopen General Reference).
READ_DEVICE_ID = 0x0E
#: §6.21, the Read Device ID codes: the basic, regular and extended streams, one object.
BASIC, REGULAR, EXTENDED, SPECIFIC = 1, 2, 3, 4
CODES = (BASIC, REGULAR, EXTENDED, SPECIFIC)
#: §6.21: "82: regular identification (stream access and individual access)".
CONFORMITY = 0x82
#: §6.21's object ids.
VENDOR_NAME, PRODUCT_CODE, MAJOR_MINOR_REVISION, PRODUCT_NAME, USER_APPLICATION_NAME = 0x00, 0x01, 0x02, 0x04, 0x06
#: The last object id of each stream's category: basic 00 … 02, regular 00 … 7Fh, extended all.
LAST = {BASIC: 0x02, REGULAR: 0x7F, EXTENDED: 0xFF}
#: §4.1: a PDU is at most 253 bytes; a response's head is 7 of them (the function code, MEI
#: type, code, conformity level, More Follows, Next Object Id, number of objects), an object's
#: id and length 2 more: "an object is indivisible", so none is longer than 244 bytes.
MAX_PDU, HEAD = 253, 7
MAX_OBJECT = MAX_PDU - HEAD - 2
_GERMAN = str.maketrans({"ä": "ae", "ö": "oe", "ü": "ue", "Ä": "Ae", "Ö": "Oe", "Ü": "Ue", "ß": "ss"})


def identification(kind: str, description: str, name: str, version: str) -> dict[int, bytes]:
    """The objects of a device of ``kind`` named ``name`` (its ``description``, devsim's
    ``version``), each as ASCII, cut to what one response can carry."""
    values = {VENDOR_NAME: "devsim", PRODUCT_CODE: kind, MAJOR_MINOR_REVISION: version,
              PRODUCT_NAME: description, USER_APPLICATION_NAME: name}
    return {i: _ascii(value)[:MAX_OBJECT] for i, value in values.items() if value}


def _ascii(text: str) -> bytes:
    return unicodedata.normalize("NFKD", text.translate(_GERMAN)).encode("ascii", "ignore")


def stream(objects: Mapping[int, bytes], code: int, first: int) -> bytes:
    """The response (after the function code) to stream ``code`` from object ``first``: "if the
    Object Id does not match any known object, the server responds as if object 0 were pointed
    out"; whole objects while they fit, then More Follows FFh and the Next Object Id."""
    ids = sorted(i for i in objects if i <= LAST[code])
    start = ids.index(first) if first in ids else 0
    body, count, more, following = b"", 0, 0x00, 0x00
    for i in ids[start:]:
        item = bytes((i, len(objects[i]))) + objects[i]
        if HEAD + len(body) + len(item) > MAX_PDU:
            more, following = 0xFF, i
            break
        body, count = body + item, count + 1
    return bytes((READ_DEVICE_ID, code, CONFORMITY, more, following, count)) + body


def individual(objects: Mapping[int, bytes], object_id: int) -> bytes:
    """The response (after the function code) to code 04 for a known object: More Follows and
    Next Object Id 00, one object."""
    value = objects[object_id]
    return bytes((READ_DEVICE_ID, SPECIFIC, CONFORMITY, 0x00, 0x00, 1, object_id, len(value))) + value
