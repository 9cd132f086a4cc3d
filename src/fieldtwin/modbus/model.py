"""The contract between the Modbus slave core and a device behind it.

The core (``fieldtwin.modbus``) decodes frames into the typed requests below,
keeps the framing rules, and asks the device to execute them.  The device (a
TES) owns its memory map, its diagnostic counters and its answer delay.
Nothing here does I/O or reads a clock: ``now`` is simulated microseconds.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import Protocol, runtime_checkable


class ExceptionCode(enum.IntEnum):
    ILLEGAL_FUNCTION = 1
    ILLEGAL_DATA_ADDRESS = 2
    ILLEGAL_DATA_VALUE = 3
    SLAVE_DEVICE_FAILURE = 4
    ACKNOWLEDGE = 5
    SLAVE_DEVICE_BUSY = 6


class Link(enum.Enum):
    """Which physical link a frame came in on (the TES count each separately)."""

    RS485 = "rs485"
    RS232 = "rs232"
    TCP = "tcp"


class Counter(enum.Enum):
    """Diagnostic counters the core reports to the device (TES manual section 7)."""

    EXCEPTION_REPLIES = "exception_replies"
    NOT_READY_REPLIES = "not_ready_replies"
    FRAMES_EXECUTED = "frames_executed"
    CRC_ERRORS = "crc_errors"
    WRONG_CHARACTERS = "wrong_characters"
    GOOD_FRAMES = "good_frames"
    NO_SILENCE = "no_silence"


@dataclass(frozen=True, slots=True)
class ReadBits:
    """fc 01 (output bits) or 02 (input bits)."""

    function: int
    address: int
    count: int


@dataclass(frozen=True, slots=True)
class ReadWords:
    """fc 03 (holding) or 04 (input)."""

    function: int
    address: int
    count: int


@dataclass(frozen=True, slots=True)
class WriteBit:
    """fc 05."""

    address: int
    value: bool


@dataclass(frozen=True, slots=True)
class WriteWord:
    """fc 06."""

    address: int
    value: int


@dataclass(frozen=True, slots=True)
class WriteBits:
    """fc 0F."""

    address: int
    values: tuple[bool, ...]


@dataclass(frozen=True, slots=True)
class WriteWords:
    """fc 10."""

    address: int
    values: tuple[int, ...]


@dataclass(frozen=True, slots=True)
class ReadExceptionStatus:
    """fc 07."""


Request = ReadBits | ReadWords | WriteBit | WriteWord | WriteBits | WriteWords | ReadExceptionStatus


class NoReply(enum.Enum):
    """A device that stays silent (unpowered, ...): the core sends nothing back."""

    NO_REPLY = "no_reply"


NO_REPLY = NoReply.NO_REPLY

# What a device answers: bits for ReadBits, words for ReadWords, an int (the
# 8-bit status) for ReadExceptionStatus, None for a write that succeeded, an
# ExceptionCode, or NO_REPLY to stay silent.
Result = tuple[bool, ...] | tuple[int, ...] | int | None | ExceptionCode | NoReply


class SlaveDevice(Protocol):
    """A Modbus slave's behaviour, as the core sees it."""

    @property
    def slave(self) -> int:
        """Slave number 1..247 this device answers to."""
        ...

    def execute(self, request: Request, link: Link, now: int, broadcast: bool) -> Result:
        """Carry out a decoded request.  ``broadcast`` requests get no reply."""
        ...

    def count(self, link: Link, counter: Counter, now: int) -> None:
        """The core saw one more of ``counter`` on ``link``."""
        ...

    def answer_delay(self, link: Link) -> int:
        """Microseconds to wait before replying (TES answer delay, 0..2570 ms)."""
        ...


# --- optional device abilities (added by the Modbus core; a device may have them) ---


@runtime_checkable
class PerLinkSlave(Protocol):
    """A device with a slave number of its own on each link (TES 3.1.3 / 3.1.4)."""

    def slave_for(self, link: Link) -> int: ...


@runtime_checkable
class LineFaultSource(Protocol):
    """A device that asks the RTU line to corrupt the next frame addressed to it.

    The line calls ``take_line_fault`` once per frame it delivers to the device;
    a fault whose ``value`` is ``"bad_crc"`` turns the frame into a CRC error,
    ``"broken_character"`` into one wrong character (the frame is dropped).
    """

    def take_line_fault(self, link: Link) -> enum.Enum | None: ...


# Counters every slave on an RTU line counts for every frame, whoever it is for.
LINE_COUNTERS = frozenset(
    (Counter.CRC_ERRORS, Counter.WRONG_CHARACTERS, Counter.GOOD_FRAMES, Counter.NO_SILENCE)
)


class LineTally:
    """The line-wide counts of one line, counted once per frame (issue 15: no O(N) per
    frame); a device that shares it adds what it counted since it joined."""

    __slots__ = ("counts",)

    def __init__(self) -> None:
        self.counts: dict[Counter, int] = dict.fromkeys(LINE_COUNTERS, 0)


@runtime_checkable
class SharedLineCounts(Protocol):
    """A device that reads the line-wide counters of ``link`` off a shared tally."""

    def share_line_counts(self, link: Link, tally: LineTally) -> None: ...
