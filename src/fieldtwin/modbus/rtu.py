"""The RTU framer on the simulated clock (TES 7.1.3, 6.2.3.2; Modbus RTU t1.5 / t3.5).

Bytes carry arrival times: a chunk that arrives at ``now`` is spread at one
character time per byte from ``max(now, end of the previous character)``, so a
chunk read late from a real transport keeps its bytes back to back.  A frame
ends when the line has been silent for t3.5 after its last character.  Inside a
frame a silence longer than t1.5 breaks it: the frame and every character up to
the next t3.5 silence are "not analysed frames by default of silent time"
(TES 6.2.3.2, counter NO_SILENCE).  A finished frame shorter than 4 bytes is
counted as wrong characters; one whose CRC does not check is first split into
back-to-back frames by their Nq / Nr lengths (TES 7.2), and what remains is one
CRC error.  The framer is sans-IO: ``receive``, ``poll``, ``next_deadline``.
"""

from __future__ import annotations

import enum
from collections.abc import Callable
from dataclasses import dataclass

from fieldtwin.errors import ProtocolError
from fieldtwin.modbus.crc import crc_ok
from fieldtwin.modbus.model import Counter
from fieldtwin.modbus.timing import RtuTiming

MIN_FRAME = 4  # TES 7.2.6: the shortest frame, slave + 07 + CRC16

LengthOf = Callable[[bytes], int | None]


@dataclass(frozen=True, slots=True)
class Frame:
    """A frame whose CRC checks, complete at ``at`` (slave number .. CRC)."""

    data: bytes
    at: int

    @property
    def slave(self) -> int:
        return self.data[0]

    @property
    def pdu(self) -> bytes:
        return self.data[1:-2]


@dataclass(frozen=True, slots=True)
class Fault:
    """``count`` more of a line counter (CRC_ERRORS, WRONG_CHARACTERS, NO_SILENCE)."""

    counter: Counter
    count: int
    at: int


FramerEvent = Frame | Fault


class State(enum.Enum):
    IDLE = "idle"  # the line has been silent for t3.5: the next character starts a frame
    RECEIVING = "receiving"  # characters at most t1.5 apart
    BROKEN = "broken"  # a silence in (t1.5, t3.5) cut the frame; wait for t3.5


class Input(enum.Enum):
    CHAR = "char"  # a chunk whose first character follows a silence <= t1.5 (or starts a frame)
    LATE_CHAR = "late_char"  # its first character follows a silence in (t1.5, t3.5)
    SILENCE = "silence"  # t3.5 since the last character
    COMPLETE = "complete"  # eager mode: the buffer held whole frames only, all handed over


def split_frames(buf: bytes, length_of: LengthOf) -> tuple[list[bytes], bytes]:
    """Back-to-back frames in ``buf`` by their lengths; returns (frames, bad rest)."""
    frames: list[bytes] = []
    while buf:
        n = length_of(buf)
        if n is not None and MIN_FRAME <= n < len(buf) and crc_ok(buf[:n]):
            frames.append(buf[:n])
            buf = buf[n:]
        elif len(buf) >= MIN_FRAME and crc_ok(buf):
            frames.append(buf)
            return frames, b""
        else:
            return frames, buf
    return frames, b""


class RtuFramer:
    """Cuts a timed byte stream into RTU frames and line faults."""

    def __init__(self, timing: RtuTiming, length_of: LengthOf) -> None:
        self.timing = timing
        self._length_of = length_of
        self.state = State.IDLE
        self._buf = bytearray()
        self._last_end = -(10**18)  # end of the last character received
        self._events: list[FramerEvent] = []
        self._table: dict[tuple[State, Input], tuple[Callable[[bytes, int], None], State]] = {
            (State.IDLE, Input.CHAR): (self._start, State.RECEIVING),
            (State.RECEIVING, Input.CHAR): (self._append, State.RECEIVING),
            (State.RECEIVING, Input.LATE_CHAR): (self._discard, State.BROKEN),
            (State.RECEIVING, Input.SILENCE): (self._finish, State.IDLE),
            (State.RECEIVING, Input.COMPLETE): (self._ignore, State.IDLE),
            (State.BROKEN, Input.CHAR): (self._ignore, State.BROKEN),
            (State.BROKEN, Input.LATE_CHAR): (self._ignore, State.BROKEN),
            (State.BROKEN, Input.SILENCE): (self._not_analysed, State.IDLE),
        }

    # -- the sans-IO surface -------------------------------------------------------

    def receive(self, data: bytes, now: int) -> list[FramerEvent]:
        """Take a chunk that arrived at ``now``; return the events it completes."""
        if data:
            start = max(now, self._last_end)
            self._settle(start)
            gap = start - self._last_end
            late = self.state is not State.IDLE and gap > self.timing.t15_us
            self._fire(Input.LATE_CHAR if late else Input.CHAR, bytes(data), start)
            self._last_end = start + len(data) * self.timing.char_us
            if self.timing.eager and self.state is State.RECEIVING:
                self._cut_complete(self._last_end)
        return self._take(now)

    def poll(self, now: int) -> list[FramerEvent]:
        """Let simulated time reach ``now``; return the events due by then."""
        self._settle(now)
        return self._take(now)

    def next_deadline(self) -> int | None:
        """When the next event is due: a frame held until its last character, or the silence."""
        if self._events:
            return self._events[0].at
        return self._silence_deadline()

    def _silence_deadline(self) -> int | None:
        if self.state is State.IDLE:
            return None
        return self._last_end + self.timing.t35_us

    # -- transitions ---------------------------------------------------------------

    def _fire(self, event: Input, data: bytes, at: int) -> None:
        try:
            action, target = self._table[(self.state, event)]
        except KeyError:
            raise ProtocolError(f"RTU framer can't handle {event} in state {self.state}") from None
        action(data, at)
        self.state = target

    def _settle(self, now: int) -> None:
        deadline = self._silence_deadline()
        if deadline is not None and deadline <= now:
            self._fire(Input.SILENCE, b"", deadline)

    def _start(self, data: bytes, at: int) -> None:
        self._buf = bytearray(data)

    def _append(self, data: bytes, at: int) -> None:
        self._buf += data

    def _discard(self, data: bytes, at: int) -> None:
        # Modbus RTU: a silence > t1.5 inside a frame makes it incomplete.
        self._buf.clear()

    def _ignore(self, data: bytes, at: int) -> None:
        pass

    def _not_analysed(self, data: bytes, at: int) -> None:
        # TES 6.2.3.2 01Dh/024h: "not analysed frames by default of silent time".
        self._events.append(Fault(Counter.NO_SILENCE, 1, at))

    def _finish(self, data: bytes, at: int) -> None:
        buf, self._buf = bytes(self._buf), bytearray()
        self._analyse(buf, at)

    def _analyse(self, buf: bytes, at: int) -> None:
        frames, rest = split_frames(buf, self._length_of)
        self._events.extend(Frame(f, at) for f in frames)
        if not rest:
            return
        if len(rest) < MIN_FRAME:
            # A fragment too short to be a frame: wrong characters (TES 6.2.3.2 01Bh).
            self._events.append(Fault(Counter.WRONG_CHARACTERS, len(rest), at))
        else:
            # TES 6.2.3.2 01Ah: "received frames with CRC16 errors".
            self._events.append(Fault(Counter.CRC_ERRORS, 1, at))

    def _cut_complete(self, last_end: int) -> None:
        """Eager mode: cut every complete, CRC-checked frame at the buffer head.

        Each frame is handed over when its own last character has arrived,
        without waiting for the t3.5 silence.
        """
        buf = self._buf
        while True:
            n = self._length_of(bytes(buf[:7]))
            if n is None or n < MIN_FRAME or len(buf) < n or not crc_ok(buf[:n]):
                return
            at = last_end - (len(buf) - n) * self.timing.char_us
            self._events.append(Frame(bytes(buf[:n]), at))
            del buf[:n]
            if not buf:
                self._fire(Input.COMPLETE, b"", last_end)
                return

    def _take(self, now: int) -> list[FramerEvent]:
        """Events due by ``now`` (an eager frame waits for its last character's time)."""
        events = self._events
        due = 0
        while due < len(events) and events[due].at <= now:
            due += 1
        taken, self._events = events[:due], events[due:]
        return taken
