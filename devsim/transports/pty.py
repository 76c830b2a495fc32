"""A pseudo-terminal that looks like a serial port (POSIX only).

The host opens the pty's *slave* side (``/dev/pts/N``, or the stable symlink given as ``link``)
exactly as it would open ``/dev/ttyS0``; the simulator serves the *master* side.  When an
existing link is replaced (one a killed simulator left) and when it is refused (a live holder's)
is :mod:`devsim.transports.ptylink`'s business.

Three things make a pty behave like a serial port rather than a terminal (see the pitfalls in
``design.md``):

* **Raw mode on both sides.**  A fresh pty cooks data: CR/LF rewriting, echo, XON/XOFF flow
  control, erase/kill characters, signals.  Both master and slave are put in raw mode
  (``cfmakeraw`` plus input flow control off), so 0x00, CR, LF, XON, XOFF and DEL pass unchanged.
  A host that reconfigures the port (pyserial does on open) sets its own termios; that is its
  business, as on a real port.
* **The slave stays open.**  The transport holds its own slave descriptor for its whole life.
  Without it, the master reports EIO/hang-up whenever no host has the port open and a naive read
  loop spins; with it, hosts can close and reopen the port any number of times.  The price: a
  pty cannot tell when a host closes the port, so this transport never calls
  ``endpoint.host_disconnected()``.
* **The host's line settings are the slave's termios.**  Host and transport share the slave
  tty, so ``tcgetattr`` on the held descriptor shows the baud rate, data bits, parity and stop
  bits the host asked for.  Before every chunk from the host (and every write to it) the termios
  are read and a change is reported through ``endpoint.host_settings()``.  At start the slave is
  preset to the endpoint's own ``serial_settings`` when it has them (a
  :class:`~devsim.transports.line.Line` does); as long as nobody has touched the termios since,
  the host counts as matching and nothing is reported.

  Linux's pty driver forces CS8 without parity whatever a host sets (``pty_set_termios``), so
  there only the baud rate and the stop bits are visible; data bits and parity are taken as the
  device's own (the host is assumed to match in what cannot be seen), and the settings say so
  (``SerialSettings.frame_seen`` false: a log shows ``9600 baud, 1 stop bit (data bits and parity
  not visible)``, never a parity the host did not set).  The transport probes
  this at start rather than assuming it.
* **Reopening at 8E1 (Linux).**  glibc's ``tcsetattr`` reads the termios back after setting
  them and fails with EINVAL when nothing changed (``c_cc`` aside) while the PARENB/CSIZE read
  back differ from the request – which on a pty is every request for parity.  So a host asking
  for even parity succeeds only if its request changes something the pty keeps: the first
  open does (speed, CLOCAL, raw mode), a second open or pyserial's reconfiguration on a change
  of ``timeout`` would not.  The transport therefore keeps the slave *armed*: CLOCAL set the
  other way than the host's last request left it, so that the host's next request (pyserial's,
  and any that sets ``CLOCAL | CREAD`` as serial code does) changes it back.  The arm is the
  ``TIOCSSOFTCAR`` ioctl, which changes that one bit under the kernel's termios lock: a host's
  change that lands while the transport arms is never set back (a whole ``tcsetattr`` read
  and written around it would).  The transport re-arms after every change of the slave's
  termios, and learns of one at once: the master is in packet mode and the slave has EXTPROC
  set, so ``pty_set_termios`` signals ``TIOCPKT_IOCTL`` to the master.  What stays impossible:
  two reconfigurations in a row faster than the transport's event loop can run between them
  (it is a different process or thread): the second one of a host asking for parity fails
  (see :func:`_arm`).

Writes towards the host never block the event loop: they are buffered and flushed when the
master is writable.  If nobody reads (no host, or a host that does not read) and more than
``max_buffer`` bytes pile up, the oldest are dropped – like a UART transmitting into an unplugged
cable.
"""

from __future__ import annotations

import array
import asyncio
import contextlib
import errno
import fcntl
import os
import sys
import termios
import time

import msgspec

from devsim.core.device import SerialSettings
from devsim.transports.base import Endpoint, Transport
from devsim.transports.ptylink import claim_link, release_link

__all__ = ["PtyTransport", "make_raw", "settings_from_termios", "apply_settings"]

_IFLAG, _OFLAG, _CFLAG, _LFLAG, _ISPEED, _OSPEED, _CC = range(7)

#: termios speed code → baud rate, from the ``termios.B*`` constants of this platform.
_SPEEDS: dict[int, int] = {
    getattr(termios, name): int(name[1:])
    for name in dir(termios)
    if name.startswith("B") and name[1:].isdigit() and int(name[1:]) > 0
}
_CODES: dict[int, int] = {baud: code for code, baud in _SPEEDS.items()}

# Linux extras pyserial uses for non-standard rates and mark/space parity.
_BOTHER = 0o010000
_TCGETS2 = 0x802C542A
_CMSPAR = getattr(termios, "CMSPAR", 0o10000000000 if sys.platform.startswith("linux") else 0)

_CSIZE_BITS = {termios.CS5: 5, termios.CS6: 6, termios.CS7: 7, termios.CS8: 8}
_BITS_CSIZE = {bits: flag for flag, bits in _CSIZE_BITS.items()}

# Linux: local-mode flag that makes the pty report every termios change to a packet-mode master.
_EXTPROC = 0o200000 if sys.platform.startswith("linux") else 0
#: Seconds an arm waits before it changes the slave (:func:`_arm`): long enough for a host to
#: read its termios back after setting them, short enough to be over before the transport's
#: loop takes the host's next bytes.  It blocks the loop, once per change of the host's settings.
ARM_PAUSE = 0.0002

#: Arms in a row at most while a host's requests keep landing between an arm and its last look.
_ARM_TRIES = 3

_TIOCPKT = getattr(termios, "TIOCPKT", None)
_TIOCPKT_DATA = 0
# Linux: sets CLOCAL alone, under the tty's termios lock (the transport's arm).
_TIOCSSOFTCAR = getattr(termios, "TIOCSSOFTCAR", 0x541A)

_READ_SIZE = 4096
#: Reads in one turn of the loop while each comes full (a flood: the next 4 KiB is often in by
#: the time the face has taken the last); a short read ends the turn, so a poll costs one read.
#: Two, not more: in ``benchmarks/noise.py`` four took noise little faster than two (70-73
#: against 65-71 MB/s) and held the neighbour's polls longer (p99 0.65-0.76 against 0.44-0.57 ms).
_FULL_READS = 2
# Device output within this many seconds of host input reuses the settings read with that input.
_RECHECK = 0.001


def make_raw(attrs: list) -> list:
    """``cfmakeraw`` on a ``tcgetattr`` list (plus IXOFF/IXANY off); returns a new list."""
    attrs = list(attrs)
    attrs[_CC] = list(attrs[_CC])
    iflag_off = (
        termios.IGNBRK
        | termios.BRKINT
        | termios.PARMRK
        | termios.ISTRIP
        | termios.INLCR
        | termios.IGNCR
        | termios.ICRNL
        | termios.IXON
        | termios.IXOFF
        | getattr(termios, "IXANY", 0)
        | getattr(termios, "IUCLC", 0)
        | getattr(termios, "IMAXBEL", 0)
    )
    attrs[_IFLAG] &= ~iflag_off
    attrs[_OFLAG] &= ~termios.OPOST
    attrs[_LFLAG] &= ~(termios.ECHO | termios.ECHONL | termios.ICANON | termios.ISIG | termios.IEXTEN)
    attrs[_CFLAG] &= ~(termios.CSIZE | termios.PARENB)
    attrs[_CFLAG] |= termios.CS8 | termios.CREAD
    attrs[_CC][termios.VMIN] = 1
    attrs[_CC][termios.VTIME] = 0
    return attrs


def _custom_speed(fd: int) -> int | None:
    """The baud rate set through ``BOTHER`` (Linux ``termios2``), if it can be read."""
    try:
        buf = array.array("i", [0] * 64)
        fcntl.ioctl(fd, _TCGETS2, buf)
    except OSError:
        return None
    return buf[10] or buf[9] or None


def settings_from_termios(attrs: list, fd: int | None = None) -> SerialSettings:
    """Line settings from a ``tcgetattr`` list (``fd`` lets non-standard rates be read)."""
    cflag = attrs[_CFLAG]
    code = attrs[_OSPEED] or attrs[_ISPEED]
    baud = _SPEEDS.get(code)
    if baud is None and code == _BOTHER and fd is not None:
        baud = _custom_speed(fd)
    if baud is None:
        baud = 0
    bytesize = _CSIZE_BITS.get(cflag & termios.CSIZE, 8)
    if not cflag & termios.PARENB:
        parity = "N"
    elif _CMSPAR and cflag & _CMSPAR:
        parity = "M" if cflag & termios.PARODD else "S"
    else:
        parity = "O" if cflag & termios.PARODD else "E"
    stopbits = 2 if cflag & termios.CSTOPB else 1
    return SerialSettings(baudrate=baud, bytesize=bytesize, parity=parity, stopbits=stopbits)


def apply_settings(attrs: list, settings: SerialSettings) -> list:
    """A ``tcgetattr`` list with the speed and frame format of ``settings`` (standard rates
    only; an unknown rate keeps the current speed)."""
    attrs = list(attrs)
    code = _CODES.get(int(settings.baudrate))
    if code is not None:
        attrs[_ISPEED] = attrs[_OSPEED] = code  # tcsetattr applies them with cfset*speed
    cflag = attrs[_CFLAG] & ~(termios.CSIZE | termios.PARENB | termios.PARODD | termios.CSTOPB | _CMSPAR)
    cflag |= _BITS_CSIZE.get(settings.bytesize, termios.CS8)
    parity = settings.parity.upper()
    if parity != "N":
        cflag |= termios.PARENB
        if parity in ("O", "M"):
            cflag |= termios.PARODD
        if parity in ("M", "S") and _CMSPAR:
            cflag |= _CMSPAR
    if float(settings.stopbits) > 1:
        cflag |= termios.CSTOPB
    attrs[_CFLAG] = cflag
    return attrs


class PtyTransport(Transport):
    """Serves an endpoint on a new pty; ``link`` is an optional stable symlink to the slave."""

    def __init__(self, link: str | os.PathLike[str] | None = None, *, max_buffer: int = 64 * 1024) -> None:
        self.link = os.fspath(link) if link is not None else None
        self.max_buffer = max_buffer
        self.address = ""
        self._master: int | None = None
        self._slave: int | None = None
        self._endpoint: Endpoint | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._out = bytearray()
        self._writing = False
        self._baseline: list | None = None
        self._touched = False
        self._reported: SerialSettings | None = None
        #: The slave's termios as last seen or armed (an arm's own change signal is then no change).
        self._last_attrs: list | None = None
        self._checked_at = -1.0
        self._preset: SerialSettings | None = None
        self._frame_visible = True
        self._packet = False
        #: Bytes dropped because nobody read them.
        self.dropped = 0

    @property
    def url(self) -> str:
        """The stable link when there is one, else the slave path."""
        return self.link or self.address

    async def start(self, endpoint: Endpoint) -> None:
        if self._master is not None:
            raise RuntimeError("transport already started")
        loop = asyncio.get_running_loop()
        master, slave = os.openpty()
        try:
            termios.tcsetattr(master, termios.TCSANOW, make_raw(termios.tcgetattr(master)))
            attrs = make_raw(termios.tcgetattr(slave))
            self._frame_visible = _pty_keeps_frame_format(slave, attrs)
            preset = getattr(endpoint, "serial_settings", None)
            if isinstance(preset, SerialSettings):
                self._preset = preset
                attrs = apply_settings(attrs, preset)
            attrs[_CFLAG] |= termios.CLOCAL  # (no modem lines; the arm below clears it, as hosts set it)
            termios.tcsetattr(slave, termios.TCSANOW, attrs)
            if not self._frame_visible:
                self._packet = _packet_mode(master)
                self._last_attrs = _arm(slave, termios.tcgetattr(slave), extproc=self._packet, pause=0.0)  # (no host yet)
            self._baseline = termios.tcgetattr(slave)
            os.set_blocking(master, False)
            self.address = os.ttyname(slave)
            if self.link is not None:
                claim_link(self.address, self.link)
        except BaseException:
            os.close(master)
            os.close(slave)
            raise
        self._master, self._slave = master, slave
        self._loop = loop
        self._endpoint = endpoint
        endpoint.attach(self._write)
        loop.add_reader(master, self._on_readable)

    async def close(self) -> None:
        if self._master is None:
            return
        loop = self._loop
        assert loop is not None
        loop.remove_reader(self._master)
        if self._writing:
            loop.remove_writer(self._master)
            self._writing = False
        if self._endpoint is not None:
            self._endpoint.attach(None)
            self._endpoint = None
        for fd in (self._master, self._slave):
            if fd is not None:
                with contextlib.suppress(OSError):
                    os.close(fd)
        self._master = self._slave = None
        self._out.clear()
        if self.link is not None:
            release_link(self.address, self.link)

    # -- host settings ----------------------------------------------------------------------
    def host_settings(self) -> SerialSettings | None:
        """The host's current settings, ``None`` while it has not touched the port."""
        if self._slave is None:
            return None
        try:
            attrs = termios.tcgetattr(self._slave)
        except termios.error:
            return None
        if not self._touched:
            if attrs == self._baseline:
                return None
            self._touched = True
        settings = settings_from_termios(attrs, self._slave)
        if not self._frame_visible:
            # The pty forced CS8 / no parity: what the host asked for is unknowable, so it
            # counts as matching the device.
            known = self._preset or SerialSettings()
            settings = msgspec.structs.replace(settings, bytesize=known.bytesize, parity=known.parity,
                                               frame_seen=False)
        return settings

    def _check_settings(self) -> None:
        # The host's termios rarely change: only decode them when the raw attributes differ.
        try:
            attrs = termios.tcgetattr(self._slave) if self._slave is not None else None
        except termios.error:
            attrs = None
        # (A host's request that lands just before an arm's last look equals that look, but may
        # have cleared EXTPROC: then the slave is armed again, or no later change is heard.)
        if attrs is not None and attrs == self._last_attrs and (not self._packet or attrs[_LFLAG] & _EXTPROC):
            return
        if attrs is not None and not self._frame_visible and self._slave is not None:
            attrs = _arm(self._slave, attrs, extproc=self._packet)
        self._last_attrs = attrs
        settings = self.host_settings()
        if settings is not None and settings != self._reported and self._endpoint is not None:
            self._reported = settings
            self._endpoint.host_settings(settings)

    # -- host → device ----------------------------------------------------------------------
    def _on_readable(self) -> None:
        for _ in range(_FULL_READS):
            if self._take() < _READ_SIZE:
                return

    def _take(self) -> int:
        """Read once and hand on what came; returns how much was read (the line's discipline
        gives at most its buffer, :data:`_READ_SIZE`: a full read means more may have come)."""
        if self._master is None:
            return 0
        try:
            data = os.read(self._master, _READ_SIZE)
        except BlockingIOError:
            return 0
        except OSError as exc:
            if exc.errno == errno.EIO:  # cannot happen while we hold the slave; be safe
                return 0
            raise
        read = len(data)
        if self._packet and data:
            status, data = data[0], data[1:]
            if status != _TIOCPKT_DATA:
                # a change of the slave's termios (TIOCPKT_IOCTL) or a flush: look at once
                if self._endpoint is not None:
                    self._check_settings()
                return 0
        if not data or self._endpoint is None:
            return 0
        if not self._packet:
            self._check_settings()  # (in packet mode every change is signalled: see above)
            self._checked_at = self._loop.time() if self._loop is not None else 0.0
        self._endpoint.feed(data)
        return read

    # -- device → host ----------------------------------------------------------------------
    def _write(self, data: bytes) -> None:
        if self._master is None or not data:
            return
        loop = self._loop
        if not self._packet and (loop is None or loop.time() - self._checked_at > _RECHECK):
            # an answer right after the host's bytes needs no second look at its termios
            self._check_settings()
        if not self._out and not self._writing:
            try:  # the common case: nothing queued – straight out (_write_some without its call)
                n = os.write(self._master, data)
            except OSError as exc:
                n = _nothing_written(exc)
            if n == len(data):
                return
            data = data[n:]
        self._out += data
        if not self._writing:
            self._flush()
        self._trim()

    def _trim(self) -> None:
        excess = len(self._out) - self.max_buffer
        if excess > 0:
            del self._out[:excess]
            self.dropped += excess

    def _flush(self) -> None:
        master = self._master
        if master is None:
            return
        while self._out:
            n = _write_some(master, self._out)
            if n <= 0:
                break
            del self._out[:n]
        assert self._loop is not None
        if self._out and not self._writing:
            self._loop.add_writer(master, self._flush)
            self._writing = True
        elif not self._out and self._writing:
            self._loop.remove_writer(master)
            self._writing = False

    @property
    def frame_visible(self) -> bool:
        """Whether the host's data bits and parity can be seen (not on Linux ptys)."""
        return self._frame_visible

    @property
    def pending(self) -> int:
        """Bytes waiting for the host to read."""
        return len(self._out)


def _write_some(fd: int, data: bytes | bytearray) -> int:
    """Write what the pty master takes now; 0 when it takes nothing (full, or no slave)."""
    try:
        return os.write(fd, data)
    except OSError as exc:
        return _nothing_written(exc)


def _nothing_written(exc: OSError) -> int:
    """0 for a write the master refused for now (full, interrupted, no slave); else raises."""
    if isinstance(exc, (BlockingIOError, InterruptedError)) or exc.errno in (errno.EIO, errno.EAGAIN):
        return 0
    raise exc


def _packet_mode(master: int) -> bool:
    """Put a Linux pty master in packet mode (so that, with EXTPROC on the slave, it hears of
    every termios change); ``False`` where that is not available."""
    if _TIOCPKT is None or not _EXTPROC:
        return False
    try:
        fcntl.ioctl(master, _TIOCPKT, array.array("i", [1]))
    except OSError:
        return False
    return True


def _arm(fd: int, attrs: list, *, extproc: bool, pause: float = ARM_PAUSE) -> list:
    """Arm a Linux pty slave for the host's next ``tcsetattr``; returns the termios now set.

    glibc's ``tcsetattr`` fails with EINVAL when the termios read back after ``TCSETS`` equal
    those read before it (``c_cc`` is not compared) and the request's PARENB or CSIZE are not
    what was read back – always the case for parity on a pty, which drops PARENB.  A host that
    repeats its request (a second open at 8E1, pyserial applying a new ``timeout``) changes
    nothing unless something differs from what its last request left.  The arm sets CLOCAL the
    other way (hosts set it: pyserial always, and the ``c_cflag |= CLOCAL | CREAD`` of serial
    code) with ``TIOCSSOFTCAR``, which changes that one bit under the tty's termios lock: a
    host's change that lands while the transport arms – a new speed right after an open – is
    kept.  (A whole ``tcsetattr`` made from a ``tcgetattr`` just before it set such a change
    back: on a busy machine a host that opened at 9600 and at once asked for 19200 was left at
    9600 about every other time.)

    An arm landing between the host's ``TCSETS`` and glibc's read-back would make the read-back
    equal what the host's call started from.  The host's change wakes the transport, often on
    the host's own processor, preempting the host right there: so the arm first sleeps
    :data:`ARM_PAUSE`, which lets the host get to its read-back (yielding the processor did not:
    on two idle processors three of four such arms still landed there).  Landing there still
    happens when something else preempted the host at that point for longer; a request that
    repeats the host's last one then fails.  ``extproc`` keeps EXTPROC set, so that a
    packet-mode master hears of the next change; only a request that dropped it (one made from
    a zeroed ``termios``) needs a whole ``tcsetattr`` to set it again.  A request that lands
    between the arm and its last look sets CLOCAL back: the arm is then made again (that look,
    taken for an armed port, made the request's own change signal look like the arm's, and the
    host's next request for parity failed, and every one after it)."""
    if pause:
        time.sleep(pause)
    try:
        if extproc and not attrs[_LFLAG] & _EXTPROC:
            whole = termios.tcgetattr(fd)
            whole[_LFLAG] |= _EXTPROC
            termios.tcsetattr(fd, termios.TCSANOW, whole)
        for attempt in range(_ARM_TRIES):
            if attempt and pause:
                time.sleep(pause)  # (that host is still in its call: let it read back first, as above)
            local = termios.tcgetattr(fd)[_CFLAG] & termios.CLOCAL
            fcntl.ioctl(fd, _TIOCSSOFTCAR, array.array("i", [0 if local else 1]))
            looked = termios.tcgetattr(fd)
            if looked[_CFLAG] & termios.CLOCAL != local:
                break
            # a host's request landed between the arm and this look and set CLOCAL back: the
            # look is no armed port (and the request's own signal would look like the arm's)
        return looked
    except (termios.error, OSError):
        return list(attrs)


def _pty_keeps_frame_format(fd: int, attrs: list) -> bool:
    """Whether this platform's pty keeps data bits and parity a host sets (Linux does not:
    ``pty_set_termios`` forces CS8 without parity)."""
    probe = list(attrs)
    probe[_CFLAG] = (probe[_CFLAG] & ~termios.CSIZE) | termios.CS7 | termios.PARENB
    try:
        termios.tcsetattr(fd, termios.TCSANOW, probe)
        cflag = termios.tcgetattr(fd)[_CFLAG]
    except termios.error:
        return False
    return (cflag & termios.CSIZE) == termios.CS7 and bool(cflag & termios.PARENB)
