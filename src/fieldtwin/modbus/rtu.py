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

Bounds (issue 10 item 5, DESIGN rule 14):

* The frame buffer never holds more than MAX_FRAME (256) bytes that are not a
  complete frame: whole, CRC-checked frames at its head are cut off as they
  complete (back-to-back frames are never dropped), and a frame that grows
  past 256 bytes is discarded; its characters up to the next t3.5 silence are
  ignored and it counts as one frame with a CRC error (TES 6.2.3.2 01Ah).  No
  CRC is ever run over more than MAX_FRAME + one chunk.
* A real line (``RtuTiming.max_lead_us`` set) cannot carry bytes faster than
  its baud rate: a chunk is placed on the line ending at its arrival time
  (back-dated into the silence before it), and characters that would end more
  than ``max_lead_us`` after their arrival are a UART overrun: lost, counted
  as wrong characters (TES 6.2.3.2 01Bh).  After a burst of any length the
  line is therefore free again at most ``max_lead_us`` + t3.5 later.
"""

from __future__ import annotations

import enum
from collections.abc import Callable
from dataclasses import dataclass

from fieldtwin.fsm import Machine, Table
from fieldtwin.modbus.crc import crc_ok
from fieldtwin.modbus.model import Counter
from fieldtwin.modbus.timing import RtuTiming

MIN_FRAME = 4  # TES 7.2.6: the shortest frame, slave + 07 + CRC16
MAX_FRAME = 256  # Modbus RTU: slave + PDU (at most 253) + CRC16
HEADER = 7  # bytes request_length needs to know a frame's length

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
    """``count`` more of a line counter (CRC_ERRORS, WRONG_CHARACTERS, NO_SILENCE), with
    why (one of REASONS) and the bytes rejected, as far as the framer kept them."""

    counter: Counter
    count: int
    at: int
    reason: str = ""
    data: bytes = b""


# Why bytes were rejected (the trace's ``reason``, docs/trace.md)
BAD_CRC = "bad_crc"  # a frame whose CRC does not check
NOISE = "noise"  # a fragment too short to be a frame
OVERRUN = "overrun"  # more than the line can carry: lost in the UART
SILENCE = "silence"  # a frame broken by a silence longer than t1.5
OVERLONG = "overlong"  # longer than any RTU frame
LINE_SETTINGS = "line_settings"  # a master at another speed or parity (runtime/uart.py)
COLLISION = "collision"  # sent while a reply was on a two-wire line (modbus/line.py)
REASONS = (BAD_CRC, NOISE, OVERRUN, SILENCE, OVERLONG, LINE_SETTINGS, COLLISION)


FramerEvent = Frame | Fault


class State(enum.Enum):
    IDLE = "idle"  # the line has been silent for t3.5: the next character starts a frame
    RECEIVING = "receiving"  # characters at most t1.5 apart
    BROKEN = "broken"  # a silence in (t1.5, t3.5) cut the frame; wait for t3.5
    OVERLONG = "overlong"  # the frame passed MAX_FRAME bytes: ignore until t3.5


class Input(enum.Enum):
    CHAR = "char"  # a chunk whose first character follows a silence <= t1.5 (or starts a frame)
    LATE_CHAR = "late_char"  # its first character follows a silence in (t1.5, t3.5)
    SILENCE = "silence"  # t3.5 since the last character
    COMPLETE = "complete"  # the buffer held whole frames only, all handed over
    OVERFLOW = "overflow"  # more than MAX_FRAME bytes that are not a complete frame


def split_frames(buf: bytes, length_of: LengthOf) -> tuple[list[bytes], bytes]:
    """Back-to-back frames in ``buf`` by their lengths; returns (frames, bad rest)."""
    frames: list[bytes] = []
    while buf:
        n = length_of(buf[:HEADER])
        if n is not None and MIN_FRAME <= n <= MAX_FRAME and n < len(buf) and crc_ok(buf[:n]):
            frames.append(buf[:n])
            buf = buf[n:]
        elif MIN_FRAME <= len(buf) <= MAX_FRAME and crc_ok(buf):
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
        self._machine: Machine[State, Input, RtuFramer] = Machine(FRAMER, State.IDLE, self)
        self._buf = bytearray()
        self._last_end = -(10**18)  # end of the last character received
        self._events: list[FramerEvent] = []
        self._broken = b""  # a frame a silence broke, for its NO_SILENCE fault

    @property
    def state(self) -> State:
        return self._machine.state

    # -- the sans-IO surface -------------------------------------------------------

    def receive(self, data: bytes, now: int) -> list[FramerEvent]:
        """Take a chunk that arrived at ``now``; return the events it completes."""
        if data:
            self._chunk(data, now)
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

    # -- one chunk -----------------------------------------------------------------

    def _chunk(self, data: bytes, now: int) -> None:
        timing = self.timing
        char = timing.char_us
        start = max(now, self._last_end)
        if timing.max_lead_us is not None:
            # a real line: the chunk was on the wire before it was read, not after
            start = max(self._last_end, now - len(data) * char)
            room = max(0, (now + timing.max_lead_us - start) // char)
            if len(data) > room:
                # TES 6.2.3.2 01Bh: characters lost to a UART overrun are wrong characters
                lost = data[room:]
                self._events.append(
                    Fault(Counter.WRONG_CHARACTERS, len(lost), now, OVERRUN, lost[:MAX_FRAME])
                )
                data = data[:room]
                if not data:
                    return
        self._settle(start)
        late = self.state is not State.IDLE and start - self._last_end > timing.t15_us
        self._last_end = start + len(data) * char
        self._machine.fire(Input.LATE_CHAR if late else Input.CHAR, data)
        if self.state is State.RECEIVING and (timing.eager or len(self._buf) > MAX_FRAME):
            self._cut(self._last_end, timing.eager)
        if self.state is State.RECEIVING and len(self._buf) > MAX_FRAME:
            self._machine.fire(Input.OVERFLOW)

    def _settle(self, now: int) -> None:
        deadline = self._silence_deadline()
        if deadline is not None and deadline <= now:
            self._machine.fire(Input.SILENCE, deadline)

    # -- actions (the table's) ------------------------------------------------------

    def _start(self, data: bytes) -> None:
        self._buf = bytearray(data)

    def _append(self, data: bytes) -> None:
        self._buf += data

    def _discard(self, data: bytes) -> None:
        # Modbus RTU: a silence > t1.5 inside a frame makes it incomplete (the bytes kept
        # for the trace, up to one frame's worth).
        self._broken = bytes(self._buf[:MAX_FRAME])
        self._buf.clear()

    def _ignore(self, data: bytes) -> None:
        pass

    def _not_analysed(self, at: int) -> None:
        # TES 6.2.3.2 01Dh/024h: "not analysed frames by default of silent time".
        broken, self._broken = self._broken, b""
        self._events.append(Fault(Counter.NO_SILENCE, 1, at, SILENCE, broken))

    def _overflow(self) -> None:
        self._buf.clear()

    def _overlong(self, at: int) -> None:
        # TES 6.2.3.2 01Ah: a frame too long to hold cannot pass its CRC check.
        self._events.append(Fault(Counter.CRC_ERRORS, 1, at, OVERLONG))

    def _finish(self, at: int) -> None:
        buf, self._buf = bytes(self._buf), bytearray()
        frames, rest = split_frames(buf, self._length_of)
        self._events.extend(Frame(f, at) for f in frames)
        if not rest:
            return
        if len(rest) < MIN_FRAME:
            # A fragment too short to be a frame: wrong characters (TES 6.2.3.2 01Bh).
            self._events.append(Fault(Counter.WRONG_CHARACTERS, len(rest), at, NOISE, rest))
        else:
            # TES 6.2.3.2 01Ah: "received frames with CRC16 errors".
            self._events.append(Fault(Counter.CRC_ERRORS, 1, at, BAD_CRC, rest))

    # -- cutting complete frames off the head --------------------------------------

    def _cut(self, last_end: int, all_done: bool) -> None:
        """Hand over every complete, CRC-checked frame at the buffer head.

        Each frame is due when its own last character has arrived, without
        waiting for the t3.5 silence (eager mode, or a buffer past MAX_FRAME).
        One pass with an offset: a chunk of many frames costs O(its length).
        """
        buf = self._buf
        view = memoryview(buf)
        size, offset = len(buf), 0
        try:
            while True:
                n = self._length_of(bytes(view[offset : offset + HEADER]))
                if n is None or not MIN_FRAME <= n <= MAX_FRAME:
                    break  # not a frame, or longer than any RTU frame may be
                end = offset + n
                if end > size or not crc_ok(view[offset:end]):
                    break
                at = last_end - (size - end) * self.timing.char_us
                self._events.append(Frame(bytes(view[offset:end]), at))
                offset = end
        finally:
            view.release()
        if offset:
            del buf[:offset]
        if not buf and all_done and offset:
            self._machine.fire(Input.COMPLETE)

    def _take(self, now: int) -> list[FramerEvent]:
        """Events due by ``now`` (an eager frame waits for its last character's time)."""
        events = self._events
        due = 0
        while due < len(events) and events[due].at <= now:
            due += 1
        taken, self._events = events[:due], events[due:]
        return taken


FRAMER: Table[State, Input] = Table(
    "RTU framer",
    State,
    Input,
    {
        (State.IDLE, Input.CHAR): (RtuFramer._start, State.RECEIVING),
        (State.RECEIVING, Input.CHAR): (RtuFramer._append, State.RECEIVING),
        (State.RECEIVING, Input.LATE_CHAR): (RtuFramer._discard, State.BROKEN),
        (State.RECEIVING, Input.SILENCE): (RtuFramer._finish, State.IDLE),
        (State.RECEIVING, Input.COMPLETE): (None, State.IDLE),
        (State.RECEIVING, Input.OVERFLOW): (RtuFramer._overflow, State.OVERLONG),
        (State.BROKEN, Input.CHAR): (RtuFramer._ignore, State.BROKEN),
        (State.BROKEN, Input.LATE_CHAR): (RtuFramer._ignore, State.BROKEN),
        (State.BROKEN, Input.SILENCE): (RtuFramer._not_analysed, State.IDLE),
        (State.OVERLONG, Input.CHAR): (RtuFramer._ignore, State.OVERLONG),
        (State.OVERLONG, Input.LATE_CHAR): (RtuFramer._ignore, State.OVERLONG),
        (State.OVERLONG, Input.SILENCE): (RtuFramer._overlong, State.IDLE),
    },
)
