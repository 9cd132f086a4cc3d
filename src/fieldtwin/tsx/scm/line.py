"""One channel's serial line: character formats, character timing, the UART.

A character takes (1 start + data + parity + stop) bit times on the line (SCM
3.2 "number of bits, parity, stop bits"); the module's UART offers only the
eight formats of 3.2.  Characters travel one clock event each: a character
leaves the transmitter when its last stop bit ends, and a burst that arrives
from a peer is received character by character at the peer's pace.

When the peer's format or speed differs from the channel's, the bit stream the
peer sends is sampled as the module's UART would (middle of each bit), which
yields the parity and format (framing) errors of SCM 6.3 "reception parity
fault" / "format fault in reception".
"""

from __future__ import annotations

import enum
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

from fieldtwin.clock import Handle

Schedule = Callable[[int, Callable[[int], None]], Handle]  # call_at(time, callback)


class Parity(enum.Enum):
    """SCM 3.2 parity codes: 0 none, 1 odd, 2 even."""

    NONE = 0
    ODD = 1
    EVEN = 2

    @property
    def letter(self) -> str:
        return {Parity.NONE: "N", Parity.ODD: "O", Parity.EVEN: "E"}[self]


@dataclass(frozen=True, slots=True)
class CharFormat:
    """A character format: data bits, parity, stop bits."""

    data_bits: int = 8
    parity: Parity = Parity.NONE
    stop_bits: int = 1

    @property
    def bits(self) -> int:
        """Bits per character on the line: start + data + parity + stop."""
        return 1 + self.data_bits + (self.parity is not Parity.NONE) + self.stop_bits

    @property
    def mask(self) -> int:
        return (1 << self.data_bits) - 1

    def __str__(self) -> str:
        return f"{self.data_bits}{self.parity.letter}{self.stop_bits}"


# SCM 3.2 "Only the eight possibilities listed below are available on each channel"
ALLOWED_FORMATS = frozenset(
    {
        CharFormat(7, Parity.EVEN, 1),
        CharFormat(7, Parity.ODD, 1),
        CharFormat(7, Parity.EVEN, 2),
        CharFormat(7, Parity.ODD, 2),
        CharFormat(8, Parity.EVEN, 1),
        CharFormat(8, Parity.ODD, 1),
        CharFormat(8, Parity.NONE, 1),
        CharFormat(8, Parity.NONE, 2),
    }
)


def char_time_us(fmt: CharFormat, baud: float) -> int:
    """Duration of one character at ``baud`` (never less than 1 us)."""
    return max(1, round(fmt.bits * 1_000_000 / baud))


def parity_bit(value: int, fmt: CharFormat) -> int:
    ones = bin(value & fmt.mask).count("1")
    return (ones + 1) % 2 if fmt.parity is Parity.ODD else ones % 2


def frame_bits(value: int, fmt: CharFormat) -> list[int]:
    """The levels of one character on the line: start (0), data LSB first, parity, stop (1)."""
    bits = [0] + [(value >> i) & 1 for i in range(fmt.data_bits)]
    if fmt.parity is not Parity.NONE:
        bits.append(parity_bit(value, fmt))
    return bits + [1] * fmt.stop_bits


@dataclass(frozen=True, slots=True)
class RxChar:
    """A character as the receiver got it, and when it ended (offset from the burst start)."""

    value: int
    parity_error: bool = False
    format_error: bool = False
    offset_us: int = 0


def decode_stream(
    data: bytes,
    sender: CharFormat,
    sender_baud: float,
    receiver: CharFormat,
    receiver_baud: float,
    *,
    invert: bool = False,
) -> list[RxChar]:
    """Characters a UART with ``receiver`` settings reads from back-to-back ``sender`` frames.

    ``invert``: the reception circuit reads every level inverted (SCM 5.1 SCA2 PSR), the
    idle line included.
    """
    levels = [b ^ invert for value in data for b in frame_bits(value, sender)]
    idle = int(not invert)
    sbit = 1.0 / sender_baud
    rbit = 1.0 / receiver_baud
    end = len(levels) * sbit

    def level(t: float) -> int:
        index = int(t / sbit)
        return levels[index] if 0 <= index < len(levels) else idle

    out: list[RxChar] = []
    t = 0.0
    while t < end:
        start = _next_low(levels, sbit, t)
        if start is None:
            break
        samples = [level(start + (k + 0.5) * rbit) for k in range(receiver.bits)]
        data_bits = samples[1 : 1 + receiver.data_bits]
        value = sum(b << i for i, b in enumerate(data_bits))
        parity_error = False
        if receiver.parity is not Parity.NONE:
            parity_error = samples[1 + receiver.data_bits] != parity_bit(value, receiver)
        stop_sample = start + (receiver.bits - receiver.stop_bits + 0.5) * rbit
        format_error = level(stop_sample) == 0
        done = start + receiver.bits * rbit
        out.append(RxChar(value, parity_error, format_error, round(done * 1_000_000)))
        t = stop_sample
    return out


def _next_low(levels: list[int], sbit: float, t: float) -> float | None:
    """First time >= t at which the line is at 0 (a start bit), None if it stays idle."""
    index = int(t / sbit)
    for i in range(max(index, 0), len(levels)):
        if levels[i] == 0:
            return max(t, i * sbit)
    return None


class Line:
    """The UART of one channel: a transmit queue and a receive queue, on the clock."""

    def __init__(self, schedule: Schedule) -> None:
        self._schedule = schedule
        self.fmt = CharFormat()
        self.baud = 9600
        self.half_speed = False  # SCA3 DSRS (SCM 5.1): half the configured speed
        self.invert_rx = False  # SCA2 PSR not matching the loop (SCM 5.1)
        self.inject_parity = False  # injected faults: every character received in error
        self.inject_format = False
        self.send_port: Callable[[bytes], None] | None = None
        self.on_sent: Callable[[int, str, int], None] = lambda value, tag, now: None
        self.on_char: Callable[[RxChar, int], None] = lambda char, now: None
        self.tx_allowed: Callable[[], bool] = lambda: True
        self._tx: deque[tuple[int, str]] = deque()
        self.in_flight: str | None = None  # tag of the character on the line
        self._tx_handle: Handle | None = None
        self._rx: deque[tuple[int, RxChar]] = deque()
        self._rx_handle: Handle | None = None
        self._rx_free = 0

    @property
    def effective_baud(self) -> float:
        return self.baud / 2 if self.half_speed else self.baud

    @property
    def char_us(self) -> int:
        return char_time_us(self.fmt, self.effective_baud)

    # --- transmitter ------------------------------------------------------

    @property
    def sending(self) -> bool:
        return self._tx_handle is not None and self._tx_handle.active

    @property
    def queued(self) -> int:
        return len(self._tx)

    def send(
        self, data: bytes | list[int], now: int, *, tag: str = "", first: bool = False
    ) -> None:
        """Queue characters (``first``: ahead of the queue, e.g. XOFF) and start sending."""
        items = [(value, tag) for value in data]
        if first:
            self._tx.extendleft(reversed(items))
        else:
            self._tx.extend(items)
        self.kick(now)

    def clear_tx(self, tag: str | None = None) -> int:
        """Drop queued characters (those with ``tag``, or all); returns how many."""
        before = len(self._tx)
        if tag is None:
            self._tx.clear()
        else:
            self._tx = deque(item for item in self._tx if item[1] != tag)
        return before - len(self._tx)

    def kick(self, now: int) -> None:
        """Start the next character if the transmitter is free and allowed (CTS, XOFF)."""
        if self.sending or not self._tx or not self.tx_allowed():
            return
        value, tag = self._tx.popleft()
        value &= self.fmt.mask
        self.in_flight = tag
        self._tx_handle = self._schedule(now + self.char_us, lambda t: self._char_out(value, t))

    def _char_out(self, value: int, now: int) -> None:
        self._tx_handle = None
        tag, self.in_flight = self.in_flight, None
        if self.send_port is not None:
            self.send_port(bytes([value]))
        self.on_sent(value, tag or "", now)
        self.kick(now)

    # --- receiver ---------------------------------------------------------

    def feed(
        self, data: bytes, now: int, sender: CharFormat | None = None, baud: float | None = None
    ) -> None:
        """Bytes from the peer at ``now``: received one by one at the sender's pace."""
        fmt, speed = sender or self.fmt, baud or self.effective_baud
        if fmt == self.fmt and speed == self.effective_baud and not self.invert_rx:
            step = self.char_us
            chars = [RxChar(v & fmt.mask, offset_us=(i + 1) * step) for i, v in enumerate(data)]
        else:
            rx_baud = self.effective_baud
            chars = decode_stream(data, fmt, speed, self.fmt, rx_baud, invert=self.invert_rx)
        base = max(now, self._rx_free)
        for char in chars:
            self._rx.append((base + char.offset_us, char))
        if self._rx:
            self._rx_free = self._rx[-1][0]
        self._arm_rx()

    def _arm_rx(self) -> None:
        if self._rx and (self._rx_handle is None or not self._rx_handle.active):
            at = self._rx[0][0]
            self._rx_handle = self._schedule(at, self._char_in)

    def _char_in(self, now: int) -> None:
        self._rx_handle = None
        while self._rx and self._rx[0][0] <= now:
            _, char = self._rx.popleft()
            self.on_char(char, now)
        self._arm_rx()

    def reset(self) -> None:
        """Power-off or reconfiguration: characters in flight are lost."""
        for handle in (self._tx_handle, self._rx_handle):
            if handle is not None:
                handle.cancel()
        self._tx_handle = self._rx_handle = None
        self.in_flight = None
        self._tx.clear()
        self._rx.clear()
        self._rx_free = 0
