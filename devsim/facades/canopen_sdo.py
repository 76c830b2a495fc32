"""The SDO server of a devsim CANopen node (issue 29; CiA 301 §7.2.4, SDO protocols and abort
codes): canopen's :class:`~canopen.sdo.SdoServer` with the request dispatch that CiA 301 asks of
an abort.  Every abort names the multiplexer (index, sub-index) of the request it answers: an
initiate request's own, a segment's the transfer in progress; a request with an unknown command
specifier (and a block transfer, which this server does not offer) is aborted 0504 0001h with the
multiplexer in its own bytes 1 … 3; a segment with no transfer in progress likewise, naming
0000h/00h (it carries no multiplexer).  An object of one value (VAR) is its sub-index 00h
alone: another sub-index of it is aborted 0609 0011h (canopen's own server answered for 00h).
A segmented download is checked at its initiation (the object, write access, the announced
size), so it is refused before any segment.  A request shorter than the 8 bytes of an SDO
frame is ignored, and so is every request while the node is STOPPED (CiA 301 §7.3.2.2: there
only NMT and the error control are served)."""

from __future__ import annotations

import logging
import struct
from collections.abc import Callable
from typing import Any

from canopen.objectdictionary import ODVariable
from canopen.objectdictionary.datatypes import BOOLEAN, NUMBER_TYPES
from canopen.sdo import SdoServer
from canopen.sdo.constants import EXPEDITED, NO_MORE_DATA, SIZE_SPECIFIED
from canopen.sdo.exceptions import SdoAbortedError

__all__ = ["INVALID_COMMAND", "DevsimSdoServer", "check_length"]

logger = logging.getLogger(__name__)

INVALID_COMMAND = 0x05040001  # client/server command specifier not valid or unknown
NOT_IN_OD = 0x06020000  # object does not exist in the object dictionary
NO_SUBINDEX = 0x06090011  # sub-index does not exist
READ_ONLY = 0x06010002  # attempt to write a read only object
LENGTH_MISMATCH = 0x06070010  # data type does not match, length of service parameter does not match
GENERAL_ERROR = 0x08000000


class DevsimSdoServer(SdoServer):
    """One node's SDO server: :data:`STEPS` by client command specifier (bits 5 … 7 of byte 0)."""

    def __init__(self, rx_cobid: int, tx_cobid: int, node: Any) -> None:
        super().__init__(rx_cobid, tx_cobid, node)
        self._index, self._subindex = 0, 0
        self.transfer: str | None = None  # "upload" / "download": a segmented transfer in progress

    def reset(self) -> None:
        """NMT reset communication: a transfer in progress ends."""
        self.transfer, self._buffer = None, None

    def on_request(self, can_id: int, data: bytes, timestamp: float) -> None:
        if len(data) < 8 or self._node.nmt.state == "STOPPED":
            return
        request = bytes(data)
        try:
            STEPS[request[0] >> 5](self, request)
        except SdoAbortedError as exc:
            self.abort(exc.code)
        except Exception:  # a fault of this server: the general error, never a dead notifier
            logger.exception("SDO request %s", request.hex())
            self.abort(GENERAL_ERROR)

    def abort(self, abort_code: int = GENERAL_ERROR) -> None:
        """The abort transfer request (CiA 301): the multiplexer of the request it answers."""
        self.transfer = None
        self.send_response(struct.pack("<BHBL", 0x80, self._index, self._subindex, abort_code))

    def _multiplexer(self, request: bytes) -> None:
        self._index, self._subindex = struct.unpack_from("<HB", request, 1)

    # -- the steps ----------------------------------------------------------------------------------
    def _initiate_upload(self, request: bytes) -> None:
        self._multiplexer(request)
        self.transfer, self._buffer = None, None
        self._variable()
        self.init_upload(request)
        if self._buffer is not None:
            self.transfer = "upload"

    def _upload_segment(self, request: bytes) -> None:
        if self.transfer != "upload":
            self._index, self._subindex = 0, 0
            raise SdoAbortedError(INVALID_COMMAND)
        self.segmented_upload(request[0])
        if not self._buffer:
            self.transfer = None

    def _initiate_download(self, request: bytes) -> None:
        self._multiplexer(request)
        self.transfer, self._buffer = None, None
        command = request[0]
        self._variable()
        if command & EXPEDITED and not command & SIZE_SPECIFIED:
            request = self._sized(request)  # (CiA 301: "d contains unspecified number of bytes")
        if not command & EXPEDITED:
            variable = self._variable()
            if not variable.writable:
                raise SdoAbortedError(READ_ONLY)
            size, = struct.unpack_from("<L", request, 4)
            if command & SIZE_SPECIFIED and variable.data_type in NUMBER_TYPES and 8 * size != len(variable):
                raise SdoAbortedError(LENGTH_MISMATCH)
        self.init_download(request)
        if not command & EXPEDITED:
            self.transfer = "download"

    def _sized(self, request: bytes) -> bytes:
        """An expedited download that does not say its size (s = 0) as one that does: as many of
        its 4 data bytes as the object's number type (or BOOLEAN, one byte) has (other objects
        take all 4)."""
        variable = self._variable()
        if not _fixed_size(variable) or not 8 <= len(variable) <= 32:
            return request
        unused = 4 - len(variable) // 8
        return bytes((request[0] | SIZE_SPECIFIED | unused << 2,)) + request[1:]

    def _download_segment(self, request: bytes) -> None:
        if self.transfer != "download":
            self._index, self._subindex = 0, 0
            raise SdoAbortedError(INVALID_COMMAND)
        self.segmented_download(request[0], request)
        if request[0] & NO_MORE_DATA:
            self.transfer = None

    def _client_abort(self, request: bytes) -> None:
        self.transfer = None
        self.request_aborted(request)

    def _unsupported(self, request: bytes) -> None:
        """A block transfer or an unknown command specifier: aborted, naming its own multiplexer."""
        self._multiplexer(request)
        raise SdoAbortedError(INVALID_COMMAND)

    def _variable(self) -> ODVariable:
        od = self._node.object_dictionary
        if self._index not in od:
            raise SdoAbortedError(NOT_IN_OD)
        entry = od[self._index]
        if isinstance(entry, ODVariable) and not self._subindex:
            return entry
        if isinstance(entry, ODVariable) or self._subindex not in entry:
            raise SdoAbortedError(NO_SUBINDEX)
        return entry[self._subindex]


def _fixed_size(variable: ODVariable) -> bool:
    """Whether ``variable``'s type has one size on the bus: the number types and BOOLEAN (one
    byte: CiA 301's BOOLEAN), not the strings and the DOMAIN."""
    return variable.data_type in NUMBER_TYPES or variable.data_type == BOOLEAN


def check_length(variable: ODVariable, data: bytes) -> None:
    """The data a download brings for ``variable``, refused 0607 0010h if its type has a size and
    this is not it.  canopen checks the number types only: a BOOLEAN of two bytes reached
    ``decode_raw`` and was the server's own fault (0800 0000h)."""
    if _fixed_size(variable) and 8 * len(data) != len(variable):
        raise SdoAbortedError(LENGTH_MISMATCH)


STEPS: dict[int, Callable[[DevsimSdoServer, bytes], None]] = {
    0: DevsimSdoServer._download_segment,
    1: DevsimSdoServer._initiate_download,
    2: DevsimSdoServer._initiate_upload,
    3: DevsimSdoServer._upload_segment,
    4: DevsimSdoServer._client_abort,
    5: DevsimSdoServer._unsupported,  # block upload
    6: DevsimSdoServer._unsupported,  # block download
    7: DevsimSdoServer._unsupported,
}
"""The client command specifiers of CiA 301's SDO protocols."""
