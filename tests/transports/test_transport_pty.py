"""PtyTransport with pyserial (and a plain file descriptor) as the host."""

from __future__ import annotations

import asyncio
import contextlib
import fcntl
import json
import os
import random
import select
import subprocess
import sys
import termios

import pytest
import serial

from devsim.core.clock import RealClock
from devsim.core.device import SerialSettings
from devsim.transports import pty as pty_module
from devsim.transports.line import Line, garble
from devsim.transports.pty import _EXTPROC, PtyTransport, _arm
from devsim.transports.ptylink import owner_record_path
from tests.transports.transport_helpers import EchoTarget, Recorder

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="ptys are POSIX only")

RAW = bytes([0x00, 0x0D, 0x0A, 0x11, 0x13, 0x7F, 0x03, 0x1A, 0x04, 0xFF])


def _serial_exchange(path: str, data: bytes, expect: int, baudrate: int = 9600) -> bytes:
    with serial.Serial(path, baudrate=baudrate, timeout=3) as port:
        port.write(data)
        port.flush()
        return port.read(expect)


def _fd_exchange(path: str, data: bytes, expect: int) -> bytes:
    """A host that does not touch termios at all: plain open/write/read."""
    fd = os.open(path, os.O_RDWR | os.O_NOCTTY)
    try:
        os.write(fd, data)
        got = b""
        while len(got) < expect:
            ready, _, _ = select.select([fd], [], [], 3)
            if not ready:
                break
            got += os.read(fd, 1024)
        return got
    finally:
        os.close(fd)


async def test_round_trip_with_pyserial(echo: Recorder) -> None:
    transport = PtyTransport()
    await transport.start(echo)
    try:
        assert transport.address.startswith("/dev/")
        got = await asyncio.to_thread(_serial_exchange, transport.address, b"#ON\r", 4)
        assert got == b"#ON\r"
        assert echo.data == b"#ON\r"
    finally:
        await transport.close()
    assert echo.write is None


@pytest.mark.parametrize("host", [_serial_exchange, _fd_exchange], ids=["pyserial", "plain-fd"])
async def test_control_bytes_pass_unchanged_both_ways(echo: Recorder, host) -> None:
    transport = PtyTransport()
    await transport.start(echo)
    try:
        got = await asyncio.to_thread(host, transport.address, RAW, len(RAW))
        assert bytes(echo.data) == RAW  # host → device
        assert got == RAW  # device → host
    finally:
        await transport.close()


async def test_device_initiated_output_is_raw(recorder: Recorder) -> None:
    transport = PtyTransport()
    await transport.start(recorder)
    try:
        fd = os.open(transport.address, os.O_RDWR | os.O_NOCTTY)
        try:
            assert recorder.write is not None
            recorder.write(RAW + b"\r\n")

            def read() -> bytes:
                got = b""
                while len(got) < len(RAW) + 2 and select.select([fd], [], [], 3)[0]:
                    got += os.read(fd, 1024)
                return got

            assert await asyncio.to_thread(read) == RAW + b"\r\n"
        finally:
            os.close(fd)
    finally:
        await transport.close()


async def test_survives_twenty_close_reopen_cycles(echo: Recorder) -> None:
    transport = PtyTransport()
    await transport.start(echo)
    try:

        def cycles() -> list[bytes]:
            answers = []
            for i in range(20):
                msg = f"#{i:02d}\r".encode()
                answers.append(_serial_exchange(transport.address, msg, len(msg)))
            return answers

        answers = await asyncio.to_thread(cycles)
        assert answers == [f"#{i:02d}\r".encode() for i in range(20)]
        # the loop did not spin on EIO between hosts and still serves
        assert await asyncio.to_thread(_fd_exchange, transport.address, b"ok", 2) == b"ok"
    finally:
        await transport.close()


async def test_stable_symlink_replaces_stale_link_and_is_removed(tmp_path, echo: Recorder) -> None:
    link = tmp_path / "sers0"
    os.symlink("/dev/pts/does-not-exist", link)  # left over by a crashed run
    transport = PtyTransport(link=str(link))
    await transport.start(echo)
    try:
        assert os.readlink(link) == transport.address
        assert transport.url == str(link)
        got = await asyncio.to_thread(_serial_exchange, str(link), b"hi", 2)
        assert got == b"hi"
    finally:
        await transport.close()
    assert not os.path.lexists(link)


async def test_refuses_to_replace_a_regular_file(tmp_path, echo: Recorder) -> None:
    path = tmp_path / "important"
    path.write_text("keep me")
    transport = PtyTransport(link=str(path))
    with pytest.raises(FileExistsError):
        await transport.start(echo)
    assert path.read_text() == "keep me"


async def test_host_settings_reported_from_slave_termios(recorder: Recorder) -> None:
    transport = PtyTransport()
    await transport.start(recorder)
    try:

        def host() -> None:
            with serial.Serial(transport.address, baudrate=4800, bytesize=7, parity="E", stopbits=2) as p:
                p.write(b"x")
                p.flush()

        await asyncio.to_thread(host)
        await recorder.wait_for(lambda: recorder.data == b"x")
        # Linux ptys force CS8 without parity: data bits and parity are reported as the
        # endpoint's own (a Recorder has none: 8N); baud and stop bits are the host's.
        reported = recorder.settings[-1]
        assert (reported.baudrate, reported.stopbits) == (4800, 2)
        assert reported.frame_seen == transport.frame_visible  # (a log does not claim what it did not see)
        if not transport.frame_visible:
            assert (reported.bytesize, reported.parity) == (8, "N")
            assert reported.describe() == "4800 baud, 2 stop bits (data bits and parity not visible)"
        else:
            assert (reported.bytesize, reported.parity) == (7, "E")
    finally:
        await transport.close()


async def test_baud_mismatch_garbles_and_matching_is_clean() -> None:
    device = SerialSettings(19200)
    target = EchoTarget(device)
    line = Line(target, RealClock())
    transport = PtyTransport()
    await transport.start(line)
    try:
        # Untouched port: preset to the device's settings, host assumed matching.
        assert line.host is None and not line.mismatch

        sent = b"#ON\r"
        seen = garble(sent, SerialSettings(9600), device)
        back = garble(seen, device, SerialSettings(9600))
        got = await asyncio.to_thread(_serial_exchange, transport.address, sent, len(back), 9600)
        assert line.host == SerialSettings(9600, frame_seen=transport.frame_visible)
        assert line.mismatch
        assert bytes(target.received) == seen != sent
        assert got == back

        target.received.clear()
        got = await asyncio.to_thread(_serial_exchange, transport.address, sent, len(sent), 19200)
        assert not line.mismatch
        assert target.received == sent
        assert got == sent
    finally:
        await transport.close()
        line.close()


async def test_output_nobody_reads_never_blocks_and_is_bounded(recorder: Recorder) -> None:
    transport = PtyTransport(max_buffer=64 * 1024)
    await transport.start(recorder)
    try:
        assert recorder.write is not None
        chunk = bytes(range(256)) * 16
        for _ in range(100):  # 400 KiB, far beyond the kernel's pty buffer
            recorder.write(chunk)
        assert transport.pending <= 64 * 1024
        assert transport.dropped > 0
    finally:
        await transport.close()


def _pour(path: str, data: bytes) -> None:
    """A host that writes ``data`` as fast as the pty takes it (plain fd, no termios)."""
    fd = os.open(path, os.O_WRONLY | os.O_NOCTTY)
    try:
        view = memoryview(data)
        while view:
            view = view[os.write(fd, view):]
    finally:
        os.close(fd)


async def test_a_flood_arrives_whole_and_in_order_a_buffer_at_a_time(recorder: Recorder) -> None:
    """A host pouring far more than the line discipline's 4 KiB buffer: the device gets every
    byte in order, in pieces no larger than one read, however many a turn of the loop takes."""
    flood = random.Random(7).randbytes(300_000)
    transport = PtyTransport()
    await transport.start(recorder)
    try:
        await asyncio.to_thread(_pour, transport.address, flood)
        await recorder.wait_for(lambda: len(recorder.data) >= len(flood), timeout=10)
        assert bytes(recorder.data) == flood
        assert max(map(len, recorder.chunks)) <= pty_module._READ_SIZE
        assert len(recorder.chunks) >= len(flood) // pty_module._READ_SIZE
    finally:
        await transport.close()


async def test_seven_bit_device_and_seven_bit_host_match() -> None:
    device = SerialSettings(9600, 7, "E", 1)
    target = EchoTarget(device)
    line = Line(target, RealClock())
    transport = PtyTransport()
    await transport.start(line)
    try:

        def host() -> bytes:
            with serial.Serial(transport.address, 9600, bytesize=7, parity="E", timeout=3) as port:
                port.write(b"#ON\r")
                return port.read(4)

        assert await asyncio.to_thread(host) == b"#ON\r"
        assert line.host is not None and line.host.baudrate == 9600
        assert not line.mismatch
        assert target.received == b"#ON\r"
    finally:
        await transport.close()
        line.close()


async def test_a_host_reopens_at_8e1_five_times_and_changes_its_timeout() -> None:
    """A GMS96 host opens 8E1: open, talk, change pyserial's ``timeout`` (which reconfigures
    the port), talk, close – five times. Linux ptys drop PARENB and glibc's tcsetattr then fails
    whenever the request changes nothing else; the transport keeps the slave armed.

    A request is made again once when it failed: an arm that lands between its TCSETS and
    glibc's read-back makes it fail (the race :func:`devsim.transports.pty._arm` documents; on two
    loaded cores about one run in eight hit it).  A transport that does not arm fails the same
    request again, and every round after the first."""
    target = EchoTarget(SerialSettings(9600, 8, "E", 1))
    line = Line(target, RealClock())
    transport = PtyTransport()
    await transport.start(line)
    again: list[str] = []

    def twice(what: str, request):
        try:
            return request()
        except (termios.error, serial.SerialException) as exc:
            again.append(f"{what}: {exc}")
            return request()

    try:

        def host(round_: int) -> bytes:
            port = twice(
                f"open {round_}", lambda: serial.Serial(transport.address, 9600, parity="E", timeout=2)
            )
            with port:
                data = bytes([0x10, round_, 0x16])
                port.write(data)
                got = port.read(len(data))
                # pyserial reconfigures the port on a new timeout: that must not fail either
                twice(f"timeout {round_}", lambda: setattr(port, "timeout", 1))
                port.write(data)
                return got + port.read(len(data))

        for round_ in range(5):
            got = await asyncio.to_thread(host, round_)
            assert got == bytes([0x10, round_, 0x16]) * 2
        assert not line.mismatch
        assert len(again) <= 2, again  # the race is rare: not every request may need a second try
    finally:
        await transport.close()
        line.close()


# A host in its own process (as a real one is: no GIL shared with the transport's loop) that
# opens the port, changes its timeout and closes it without sending a byte, then talks once.
# Between its requests it waits until the transport has armed the slave (CLOCAL the other way
# than pyserial sets it): a real host cannot see that, and only a request that comes faster than
# the transport's loop can run is refused (see devsim.transports.pty).  What stays possible is an
# arm that lands between a request's TCSETS and glibc's read-back, when the machine keeps the host
# off its processor there for longer than ARM_PAUSE (seen on two loaded cores): that request fails
# once and is made again (counted on stderr).  A transport that did not arm fails every request
# after the first open twice.
_QUIET_HOST = r"""
import sys, termios, time, serial
path, parity = sys.argv[1], sys.argv[2]
log, again = [], []

def armed(port):
    deadline = time.monotonic() + 10
    while termios.tcgetattr(port.fd)[2] & termios.CLOCAL:
        if time.monotonic() > deadline:
            log.append("never armed")
            return
        time.sleep(0.001)

def twice(what, action):
    for attempt in range(2):
        try:
            return action()
        except Exception as exc:
            (again if attempt == 0 else log).append(f"{what}: {exc}")

def set_timeout(port):
    port.timeout = 1
    return True

for i in range(5):
    port = twice(f"open {i}", lambda: serial.Serial(path, 9600, parity=parity, timeout=2))
    if port is None:
        continue
    armed(port)
    twice(f"timeout {i}", lambda: set_timeout(port))
    armed(port)
    port.close()
port = twice("open to talk", lambda: serial.Serial(path, 9600, parity=parity, timeout=2))
if port is not None:
    port.write(b"\x10\x7b\x16")
    if port.read(3) != b"\x10\x7b\x16":
        log.append("no echo")
    port.close()
print("made again: " + "; ".join(again), file=sys.stderr)
print("; ".join(log) or "ok")
"""


@pytest.mark.parametrize("parity", ["E", "O", "N"])
async def test_a_quiet_host_reopens_and_reconfigures_at_any_parity(parity: str) -> None:
    """No traffic between the opens: the transport hears of each termios change from the pty
    itself (packet mode, EXTPROC) and re-arms the slave, instead of waiting for data."""
    target = EchoTarget(SerialSettings(9600, 8, parity, 1))
    line = Line(target, RealClock())
    transport = PtyTransport()
    await transport.start(line)
    try:
        proc = await asyncio.create_subprocess_exec(
            sys.executable,
            "-c",
            _QUIET_HOST,
            transport.address,
            parity,
            stdout=asyncio.subprocess.PIPE,
            stderr=asyncio.subprocess.PIPE,
        )
        out, err = await asyncio.wait_for(proc.communicate(), 30)
        assert out.decode().strip() == "ok", err.decode()
        assert line.host is not None and line.host.baudrate == 9600
    finally:
        await transport.close()
        line.close()


async def test_arming_keeps_the_hosts_speed_and_stop_bits() -> None:
    """Re-arming touches only CLOCAL (and EXTPROC): what the host set stays set."""
    transport = PtyTransport()
    target = EchoTarget(SerialSettings(4800, 8, "E", 2))
    line = Line(target, RealClock())
    await transport.start(line)
    try:

        def host() -> None:
            with serial.Serial(transport.address, 4800, parity="E", stopbits=2, timeout=2) as port:
                port.write(b"x")
                assert port.read(1) == b"x"
                port.timeout = 1
                port.write(b"y")
                assert port.read(1) == b"y"

        await asyncio.to_thread(host)
        assert line.host == SerialSettings(4800, 8, "E", 2, frame_seen=transport.frame_visible) and not line.mismatch
    finally:
        await transport.close()
        line.close()


def test_arming_does_not_set_back_a_speed_the_host_set_after_the_look() -> None:
    """The arm after a termios change is made from the termios as they are when it is set, not
    as the transport read them before: a host that opens the port and at once sets another speed
    (its change landing between the transport's look and its arm) keeps its speed.  The look is
    made stale here on purpose: the host's 19200 baud comes after the 9600 the arm is given."""
    master, slave = os.openpty()
    try:
        looked = termios.tcgetattr(slave)
        looked[4] = looked[5] = termios.B9600
        termios.tcsetattr(slave, termios.TCSANOW, looked)
        host = termios.tcgetattr(slave)
        host[4] = host[5] = termios.B19200
        termios.tcsetattr(slave, termios.TCSANOW, host)  # the host's change, after the look
        armed = _arm(slave, looked, extproc=True)
        assert termios.tcgetattr(slave)[4:6] == [termios.B19200, termios.B19200] == armed[4:6]
    finally:
        os.close(master)
        os.close(slave)


class _HostAsksForNineteenTwoHundred:
    """The pty module's ``termios``, but the first look the transport takes is followed at once
    by a host's ``tcsetattr`` for 19200 baud: the worst moment a host's change can land."""

    def __init__(self, host: int) -> None:
        self.host = host
        self.request: list | None = None

    def __getattr__(self, name: str):
        return getattr(termios, name)

    def tcgetattr(self, fd: int) -> list:
        attrs = termios.tcgetattr(fd)
        if self.request is None:
            self.request = termios.tcgetattr(self.host)
            self.request[4] = self.request[5] = termios.B19200
            termios.tcsetattr(self.host, termios.TCSANOW, self.request)
        return attrs


def test_a_host_change_that_lands_while_the_transport_arms_is_kept(monkeypatch: pytest.MonkeyPatch) -> None:
    """The arm changes one bit (CLOCAL) under the kernel's termios lock, so a host's new speed
    that lands between the arm's look at the termios and its change is kept.  A whole
    ``tcsetattr`` made from that look set it back (on a busy machine a host that opened at 9600
    and at once asked for 19200 was left at 9600 about every other time).  The host's change is
    put in at exactly that point here; the arm must still leave CLOCAL the other way than the
    host's request, so that the same request again is a change."""
    master, slave = os.openpty()
    host = os.open(os.ttyname(slave), os.O_RDWR | os.O_NOCTTY)
    try:
        start = termios.tcgetattr(slave)
        start[3] |= _EXTPROC
        start[4] = start[5] = termios.B9600
        termios.tcsetattr(slave, termios.TCSANOW, start)
        middle = _HostAsksForNineteenTwoHundred(host)
        monkeypatch.setattr(pty_module, "termios", middle)
        armed = _arm(slave, termios.tcgetattr(slave), extproc=True)
        monkeypatch.undo()
        assert middle.request is not None
        assert termios.tcgetattr(host)[4:6] == [termios.B19200, termios.B19200] == armed[4:6]
        assert armed[2] & termios.CLOCAL != middle.request[2] & termios.CLOCAL
    finally:
        for fd in (host, master, slave):
            os.close(fd)


def _raw(fd: int, speed: int) -> None:
    """A host's raw mode from a zeroed ``c_lflag`` (as C code and the live-log tests set it):
    EXTPROC goes with it."""
    attrs = termios.tcgetattr(fd)
    attrs[0] = attrs[1] = attrs[3] = 0
    attrs[2] |= termios.CLOCAL | termios.CREAD
    attrs[4] = attrs[5] = speed
    termios.tcsetattr(fd, termios.TCSANOW, attrs)


class _HostRepeatsItsRequestAsTheArmEnds:
    """The pty module's ``fcntl``, but right after the arm's ``TIOCSSOFTCAR`` the host sets its
    raw 4800 baud again (a second open, or a host that sets its port twice): its change lands
    between the arm and the transport's last look, and it clears EXTPROC."""

    def __init__(self, host: int) -> None:
        self.host = host
        self.fired = False

    def __getattr__(self, name: str):
        return getattr(fcntl, name)

    def ioctl(self, fd: int, request: int, arg):
        result = fcntl.ioctl(fd, request, arg)
        if request == pty_module._TIOCSSOFTCAR and not self.fired:
            self.fired = True
            self.request()
        return result

    def request(self) -> None:
        _raw(self.host, termios.B4800)


class _HostRepeatsItsSerialRequestAsTheArmEnds(_HostRepeatsItsRequestAsTheArmEnds):
    """The same, but the host's request is serial code's (pyserial's): read, CLOCAL | CREAD and
    the speed set, written back; EXTPROC stays."""

    def request(self) -> None:
        attrs = termios.tcgetattr(self.host)
        attrs[2] |= termios.CLOCAL | termios.CREAD
        attrs[4] = attrs[5] = termios.B4800
        termios.tcsetattr(self.host, termios.TCSANOW, attrs)


@contextlib.asynccontextmanager
async def _host_heard():
    """A transport with a raw host on its slave, and a queue of the settings the line hears."""
    line = Line(EchoTarget(SerialSettings(9600, 8, "N", 1)), RealClock())
    heard: asyncio.Queue[str] = asyncio.Queue()
    line.observers.append(lambda event, text: heard.put_nowait(text) if event == "host_settings" else None)
    transport = PtyTransport()
    await transport.start(line)
    host = os.open(transport.address, os.O_RDWR | os.O_NOCTTY)
    try:
        yield host, heard
    finally:
        os.close(host)
        await transport.close()
        line.close()


async def test_a_host_that_repeats_its_request_as_the_arm_ends_finds_the_port_armed(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """A host's request that lands between the arm and the transport's last look (a second open
    at once, pyserial setting its port twice) sets CLOCAL back: that look is not an armed port,
    and the host's next request asking for parity must still be a change.  Found by the soak of a
    real ``devsim run ip247 --pty``: the transport took that look for its arm, the host's change
    signal then looked like the arm's own, and every later open at 8E1 failed with EINVAL (the
    slave stayed at ``clocal extproc``) until the host asked for something else."""
    async with _host_heard() as (host, heard):
        middle = _HostRepeatsItsSerialRequestAsTheArmEnds(host)
        monkeypatch.setattr(pty_module, "fcntl", middle)
        attrs = termios.tcgetattr(host)
        attrs[2] |= termios.CLOCAL | termios.CREAD
        attrs[4] = attrs[5] = termios.B4800
        termios.tcsetattr(host, termios.TCSANOW, attrs)
        assert "4800 baud" in await asyncio.wait_for(heard.get(), 5)
        assert middle.fired
        monkeypatch.undo()
        assert not termios.tcgetattr(host)[2] & termios.CLOCAL  # armed: the other way than the host's request
        attrs = termios.tcgetattr(host)
        attrs[2] |= termios.CLOCAL | termios.CREAD | termios.PARENB
        termios.tcsetattr(host, termios.TCSANOW, attrs)  # (8E1 again: a change, no EINVAL)


async def test_a_host_that_clears_extproc_as_the_arm_ends_is_still_heard(monkeypatch: pytest.MonkeyPatch) -> None:
    """The transport's last look after an arm is what its own change signal is compared with.
    A raw host's request that lands just before that look (two opens in a row) clears EXTPROC
    and is taken for the arm's own change: the transport must set EXTPROC again, or it hears of
    no later change of the host's (CI saw a host's 19200 baud go unreported this way)."""
    async with _host_heard() as (host, heard):
        middle = _HostRepeatsItsRequestAsTheArmEnds(host)
        monkeypatch.setattr(pty_module, "fcntl", middle)
        _raw(host, termios.B4800)
        assert "4800 baud" in await asyncio.wait_for(heard.get(), 5)
        assert middle.fired  # (the transport arms before it reports the settings)
        monkeypatch.undo()
        _raw(host, termios.B19200)
        assert "19200 baud" in await asyncio.wait_for(heard.get(), 5)


@pytest.mark.parametrize("target", ["elsewhere", "live-pty"])
async def test_refuses_to_repoint_a_link_devsim_did_not_leave(tmp_path, echo: Recorder, target: str) -> None:
    """Only a link to a vanished pseudo-terminal (a killed simulator's) is replaced; a symlink to
    a user's file or to another simulator's live pty stays, and is not deleted on stop."""
    link = tmp_path / "tty"
    other = PtyTransport()
    await other.start(Recorder())
    try:
        aim = str(tmp_path / "notes.txt") if target == "elsewhere" else other.address
        os.symlink(aim, link)
        transport = PtyTransport(link=str(link))
        with pytest.raises(FileExistsError, match="not replacing it|in use"):
            await transport.start(echo)
        await transport.close()
        assert os.readlink(link) == aim
    finally:
        await other.close()


async def test_a_link_whose_recorded_holder_is_dead_is_replaced_even_onto_a_live_pty(tmp_path, echo: Recorder) -> None:
    """The pty number of a killed simulator is soon someone else's: the owner record, not the
    pty's existence, decides (a pid that has exited, here a finished child)."""
    link = tmp_path / "tty"
    other = PtyTransport()
    await other.start(Recorder())
    child = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True,
                           text=True, check=True)
    try:
        os.symlink(other.address, link)
        owner_record_path(str(link)).write_text(json.dumps({"pid": int(child.stdout), "pty": other.address}))
        transport = PtyTransport(link=str(link))
        await transport.start(echo)
        try:
            assert os.readlink(link) == transport.address
            assert json.loads(owner_record_path(str(link)).read_text())["pid"] == os.getpid()
            assert await asyncio.to_thread(_serial_exchange, str(link), b"hi", 2) == b"hi"
        finally:
            await transport.close()
        assert not os.path.lexists(link) and not owner_record_path(str(link)).exists()
    finally:
        await other.close()
