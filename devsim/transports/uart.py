"""The UARTs at both ends of a line: whether their settings match, and what a receiver reads
when they do not (a bit-level model; see :func:`garble`).

Pure functions, no clock, no I/O; :mod:`devsim.transports.line` uses them and re-exports both.
"""

from __future__ import annotations

from devsim.core.device import SerialSettings

__all__ = ["garble", "settings_match"]


def settings_match(a: SerialSettings, b: SerialSettings) -> bool:
    """True when two UARTs with these settings understand each other."""
    return (
        a.baudrate == b.baudrate
        and a.bytesize == b.bytesize
        and a.parity.upper() == b.parity.upper()
        and float(a.stopbits) == float(b.stopbits)
    )


def _parity_bit(value: int, bytesize: int, parity: str) -> int | None:
    parity = parity.upper()
    if parity == "N":
        return None
    ones = bin(value & ((1 << bytesize) - 1)).count("1")
    if parity == "E":
        return ones & 1
    if parity == "O":
        return (ones & 1) ^ 1
    if parity == "M":
        return 1
    if parity == "S":
        return 0
    raise ValueError(f"unknown parity {parity!r}")


def _waveform(data: bytes, tx: SerialSettings) -> list[int]:
    """The sender's line level in half-bit steps (half bits make 1.5 stop bits exact)."""
    stop_halves = round(float(tx.stopbits) * 2)
    levels: list[int] = []
    for byte in data:
        levels += [0, 0]  # start bit
        for i in range(tx.bytesize):
            bit = (byte >> i) & 1
            levels += [bit, bit]
        parity = _parity_bit(byte, tx.bytesize, tx.parity)
        if parity is not None:
            levels += [parity, parity]
        levels += [1] * stop_halves
    return levels


def garble(data: bytes, sender: SerialSettings, receiver: SerialSettings) -> bytes:
    """What a UART configured with ``receiver`` reads when a UART configured with ``sender``
    transmits ``data`` back to back (one burst, idle line before and after).

    A deterministic, pure model of the receiver: it waits for the line to be low, confirms the
    start bit in its middle, samples each data bit, the parity bit and the stop bit in the middle
    of *its own* bit cells.  A character with a framing error (stop bit sampled low) is handed
    over as sampled – the garbage a device's UART register holds; a receiver configured for
    parity checks it and hands over a character with a parity error as NUL (what a POSIX port
    with ``INPCK`` delivers), so a 7E1 device never mistakes 8N1 ASCII for its own.  After the
    stop bit sample it looks for the next start bit (resynchronising at once after a framing
    error, as a 16550 does).  A break – the line low from the start bit through the stop bit
    sample – reads as one NUL, however long it lasts, and then the character its end cuts (so a
    sender far slower, or a receiver far faster, costs two characters per low stretch, not
    thousands).
    A side at 0 baud (a host that set B0, POSIX's hang-up) gets nothing across either way.

    A faster sender squeezes several characters into one received character; a slower sender's
    single character is read as a character plus framing garbage.  With matching settings the
    output equals the input.  Time is counted in integer units (``1 / (4 * tx_baud * rx_baud)``
    seconds) so the result never depends on floating-point rounding.
    """
    if not data:
        return b""
    if settings_match(sender, receiver):
        return bytes(data)
    tx_baud, rx_baud = int(sender.baudrate), int(receiver.baudrate)
    if tx_baud <= 0 or rx_baud <= 0:  # B0: a hung-up port (or a rate a pty did not show): nothing gets across
        return b""
    levels = _waveform(data, sender)
    half = 2 * rx_baud  # one sender half bit, in time units
    rx_bit = 4 * tx_baud  # one receiver bit, in time units
    end = len(levels) * half

    def level(t: int) -> int:
        h = t // half
        return levels[h] if 0 <= h < len(levels) else 1

    def next_high(t: int) -> int:
        h = t // half
        while h < len(levels) and levels[h] == 0:
            h += 1
        return max(t, h * half)  # (after the waveform the line idles at mark)

    def next_low(t: int) -> int | None:
        h = t // half
        if h < len(levels) and levels[h] == 0:
            return t
        h += 1
        while h < len(levels):
            if levels[h] == 0:
                return h * half
            h += 1
        return None

    rx_parity = receiver.parity.upper() != "N"
    out = bytearray()
    t = 0
    while t < end:
        edge = next_low(t)
        if edge is None:
            break
        # Middle of the start bit: a glitch shorter than half a bit is not a start bit.
        if level(edge + rx_bit // 2) != 0:
            t = edge + rx_bit // 2 + 1
            continue
        value = 0
        for i in range(receiver.bytesize):
            value |= level(edge + (2 * (i + 1) + 1) * rx_bit // 2) << i
        cells = 1 + receiver.bytesize
        if rx_parity:
            sampled = level(edge + (2 * cells + 1) * rx_bit // 2)
            cells += 1
            if sampled != _parity_bit(value, receiver.bytesize, receiver.parity):
                value = 0  # parity error: reported as NUL, as a POSIX port with INPCK does
        stop_sample = edge + (2 * cells + 1) * rx_bit // 2
        out.append(value)  # a framing error (low stop bit) still delivers what was sampled
        t = stop_sample
        rise = next_high(edge)
        if rise > stop_sample:
            # A break (the line low from the start bit through the stop bit sample) is one NUL, as
            # a 16550 reports it once (LSR BI), not one per frame time: the frames wholly inside
            # it are skipped, up to the one the line's rise cuts.  [SIM-CHOICE] that one is still
            # read as before (the framing garbage a slow sender's character leaves).
            t = edge + (rise - edge - 1) // (stop_sample - edge) * (stop_sample - edge)
    return bytes(out)
