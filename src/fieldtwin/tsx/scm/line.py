"""One channel's serial line: character formats, character timing, the UART.

A character takes (1 start + data + parity + stop) bit times on the line (SCM
3.2 "number of bits, parity, stop bits"); the module's UART offers only the
eight formats of 3.2.  The format is the kernel's
:class:`fieldtwin.charformat.CharFormat` (speed included).  Characters travel
one clock event each: a character leaves the transmitter when its last stop
bit ends, and a burst that arrives from a peer is received character by
character at the peer's pace.

When the peer's format or speed differs from the channel's, the bit stream the
peer sends is sampled as the module's UART would (middle of each bit), which
yields the parity and format (framing) errors of SCM 6.3 "reception parity
fault" / "format fault in reception".

The receiver is bounded (DESIGN rule 14, docs/manual-notes.md "SCM overrun"):
at most ``RX_BACKLOG`` characters may wait for the wire.  A peer that writes
faster than the line carries them (a pty or TCP peer is not held back by a
baud rate) loses what it writes beyond that, as a UART overruns when
characters come faster than it takes them; ``on_overrun`` tells the channel.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

from fieldtwin.charformat import US_PER_S, CharFormat, Parity
from fieldtwin.clock import Handle

Schedule = Callable[[int, Callable[[int], None]], Handle]  # call_at(time, callback)

# SCM 3.2 "Only the eight possibilities listed below are available on each channel"
ALLOWED_FRAMES = frozenset({"7E1", "7O1", "7E2", "7O2", "8E1", "8O1", "8N1", "8N2"})
# The most characters a peer may be ahead of the line: what the module counts as
# received, SCM 5.2 IWxy,4 "between 1 and 256" (a request takes at most 254, 4.2/4.4).
RX_BACKLOG = 256
# Echo characters the transmitter may hold: three per character of the backlog
# (a back-space is echoed BS SP BS, SCM 3.2); more is an echo that cannot keep up.
ECHO_BACKLOG = 3 * RX_BACKLOG


def allowed(fmt: CharFormat) -> bool:
    """One of the eight formats of SCM 3.2 (any speed)."""
    return fmt.frame in ALLOWED_FRAMES


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
    receiver: CharFormat,
    *,
    sender_baud: float | None = None,
    receiver_baud: float | None = None,
    invert: bool = False,
) -> list[RxChar]:
    """Characters a UART with ``receiver`` settings reads from back-to-back ``sender`` frames.

    The speeds are the formats' own unless given (a half-speed receiver, SCM 5.1 DSRS).
    ``invert``: the reception circuit reads every level inverted (SCM 5.1 SCA2 PSR), the
    idle line included.
    """
    levels = [b ^ invert for value in data for b in frame_bits(value, sender)]
    idle = int(not invert)
    sbit = 1.0 / (sender_baud or sender.baud)
    rbit = 1.0 / (receiver_baud or receiver.baud)
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
        out.append(RxChar(value, parity_error, format_error, round(done * US_PER_S)))
        t = stop_sample
    return out


def _next_low(levels: list[int], sbit: float, t: float) -> float | None:
    """First time >= t at which the line is at 0 (a start bit), None if it stays idle."""
    index = int(t / sbit)
    for i in range(max(index, 0), len(levels)):
        if levels[i] == 0:
            return max(t, i * sbit)
    return None


def _ignore_overrun(lost: int, now: int) -> None:
    pass


class Line:
    """The UART of one channel: a transmit queue and a bounded receive queue, on the clock."""

    def __init__(self, schedule: Schedule) -> None:
        self._schedule = schedule
        self.fmt = CharFormat(9600, 8, Parity.NONE, 1)
        self.half_speed = False  # SCA3 DSRS (SCM 5.1): half the configured speed
        self.invert_rx = False  # SCA2 PSR not matching the loop (SCM 5.1)
        self.inject_parity = False  # injected faults: every character received in error
        self.inject_format = False
        self.send_port: Callable[[bytes], None] | None = None
        self.on_sent: Callable[[int, str, int], None] = lambda value, tag, now: None
        self.on_char: Callable[[RxChar, int], None] = lambda char, now: None
        self.on_overrun: Callable[[int, int], None] = _ignore_overrun
        self.tx_allowed: Callable[[], bool] = lambda: True
        self.overruns = 0  # characters lost because they came faster than the line
        self.echo_dropped = 0  # echo characters the transmitter had no room for
        self._tx: deque[tuple[int, str]] = deque()
        self.in_flight: str | None = None  # tag of the character on the line
        self._tx_handle: Handle | None = None
        self._rx: deque[tuple[int, RxChar]] = deque()
        self._rx_handle: Handle | None = None
        self._rx_free = 0

    @property
    def baud(self) -> int:
        """The configured speed (SCM 3.2)."""
        return self.fmt.baud

    @property
    def effective_baud(self) -> float:
        return self.fmt.baud / 2 if self.half_speed else self.fmt.baud

    @property
    def char_us(self) -> int:
        """One character on the line, in whole microseconds (twice as long at half speed)."""
        return max(1, round(self.fmt.char_time * (2 if self.half_speed else 1)))

    # --- transmitter ------------------------------------------------------

    @property
    def sending(self) -> bool:
        return self._tx_handle is not None and self._tx_handle.active

    @property
    def queued(self) -> int:
        return len(self._tx)

    def send(
        self,
        data: bytes | list[int],
        now: int,
        *,
        tag: str = "",
        first: bool = False,
        limit: int | None = None,
    ) -> None:
        """Queue characters (``first``: ahead of the queue, e.g. XOFF) and start sending.

        ``limit``: queue only up to that many characters in all (an echo); the rest is
        dropped and counted in ``echo_dropped``.
        """
        items = [(value, tag) for value in data]
        if limit is not None:
            room = max(0, limit - len(self._tx))
            self.echo_dropped += max(0, len(items) - room)
            items = items[:room]
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

    @property
    def backlog(self) -> int:
        """Characters on their way in (sent by the peer, not yet received)."""
        return len(self._rx)

    def feed(
        self, data: bytes, now: int, sender: CharFormat | None = None, *, peer_speed: bool = True
    ) -> None:
        """Bytes from the peer at ``now``: received one by one at the sender's pace.

        ``sender``: the peer's format (None: the channel's own); ``peer_speed`` False: the
        peer sends at the line's present speed whatever its format says.  Work and memory
        are bounded by ``RX_BACKLOG``: what does not fit is lost (an overrun).
        """
        room = RX_BACKLOG - len(self._rx)
        kept = data[: max(0, room)]
        chars = self._decode(kept, sender, peer_speed)[: max(0, room)]
        lost = len(data) - len(kept)
        base = max(now, self._rx_free)
        for char in chars:
            self._rx.append((base + char.offset_us, char))
        if self._rx:
            self._rx_free = self._rx[-1][0]
        if lost:
            self.overruns += lost
            self.on_overrun(lost, now)
        self._arm_rx()

    def _decode(self, data: bytes, sender: CharFormat | None, peer_speed: bool) -> list[RxChar]:
        fmt = sender or self.fmt
        speed = fmt.baud if peer_speed and sender is not None else self.effective_baud
        same = fmt.frame == self.fmt.frame and speed == self.effective_baud
        if same and not self.invert_rx:
            step = self.char_us
            return [RxChar(v & fmt.mask, offset_us=(i + 1) * step) for i, v in enumerate(data)]
        return decode_stream(
            data,
            fmt,
            self.fmt,
            sender_baud=speed,
            receiver_baud=self.effective_baud,
            invert=self.invert_rx,
        )

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


__all__ = [
    "ALLOWED_FRAMES",
    "ECHO_BACKLOG",
    "RX_BACKLOG",
    "CharFormat",
    "Line",
    "Parity",
    "RxChar",
    "allowed",
    "decode_stream",
]
