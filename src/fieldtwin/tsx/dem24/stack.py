"""Logging messages (DEM 4.2-2) and the 200-message stack (2.3-4).

A message is 13 words (26 bytes).  Word 0 (messages in the exchange, exchange
number) is filled when the message is read; word 1 holds the stack-overflow flag
(bit C), the type (bit A), the H synchronization flag (bit 8) and the modification
indicator (bits 7..0) (AMB-DEM-05).
"""

from __future__ import annotations

import enum
from collections import deque
from typing import NamedTuple

from fieldtwin.tsx.dem24.civil import CivilTime

MESSAGE_WORDS = 13
MESSAGE_BYTES = 26
STACK_SIZE = 200  # DEM 2.3-4
NEARLY_FULL = 140  # 70 % of the stack (DEM 1.2-1 "70 % full")
READ_MAX = 9  # DEM 4.2-1: 1 to 9 messages per read

# Word 1 fields (DEM 4.2-2, AMB-DEM-05)
STACK_BIT = 12
TYPE_BIT = 10
H_BIT = 8

# Channel numbers of DEM 4.2-2
CH_SYNC = 24  # loss of synchronization
CH_TERMINAL = 25  # terminal block missing
CH_SUPPLY = 26  # external supply fault

STATE_OFF = 0
STATE_ON = 1
STATE_OSCILLATING = 2


Body = tuple[int, int, int, int, int, int]  # words 7..12


class MessageType(enum.IntEnum):
    CHANGE = 0  # change of an input state
    OVERALL = 1  # general state of the inputs


class Message(NamedTuple):
    """One logged message; ``body`` is words 7..12 (6 words).

    A named tuple, as :class:`CivilTime`: one is made for every message logged."""

    type: MessageType
    stamp: CivilTime
    h: bool  # synchronization fault at logging time
    indicator: int  # modification indicator in force
    rack: int
    slot: int
    body: Body
    overflow: bool = False  # at least one message lost before this one

    @property
    def channel(self) -> int:
        return self.body[0] >> 8

    @property
    def state(self) -> int:
        return self.body[0] & 0xFF

    def flagged(self) -> Message:
        return self._replace(overflow=True)

    def words(self, exchange: int, count: int) -> list[int]:
        """The 13 words of DEM 4.2-2 (binary bytes, AMB-DEM-07)."""
        s = self.stamp
        word1 = (
            (int(self.overflow) << STACK_BIT)
            | (int(self.type) << TYPE_BIT)
            | (int(self.h) << H_BIT)
            | (self.indicator & 0xFF)
        )
        return [
            ((count & 0xFF) << 8) | (exchange & 0xFF),
            word1,
            (s.yy << 8) | s.month,
            (s.day << 8) | s.hour,
            (s.minute << 8) | s.second,
            s.ms,
            ((self.rack & 0xFF) << 8) | (self.slot & 0xFF),
            *self.body,
        ]


def change_body(channel: int, state: int) -> Body:
    """Words 7..12 of a change message: channel / state, then reserved = 0 (AMB-DEM-21)."""
    return ((channel << 8) | state, 0, 0, 0, 0, 0)


def overall_body(
    selected: int, oscillating: int, states: int, faults: tuple[bool, bool, bool]
) -> Body:
    """Words 7..12 of an overall-state message: 24-bit vectors, faults 24..26 (AMB-DEM-06)."""
    status = states | sum(int(f) << (24 + i) for i, f in enumerate(faults))
    return (
        selected & 0xFFFF,
        (selected >> 16) & 0xFF,
        oscillating & 0xFFFF,
        (oscillating >> 16) & 0xFF,
        status & 0xFFFF,
        (status >> 16) & 0x07FF,
    )


class MessageStack:
    """Oldest first; a message that finds the stack full is lost and flagged in the next."""

    def __init__(self, size: int = STACK_SIZE) -> None:
        self.size = size
        self._messages: deque[Message] = deque()
        self.lost = 0  # messages lost since the last one stored
        self.total_lost = 0
        self.total_stored = 0

    def __len__(self) -> int:
        return len(self._messages)

    @property
    def full(self) -> bool:
        return len(self._messages) >= self.size

    def push(self, message: Message) -> bool:
        """Store ``message``; False (and counted) when the stack is full."""
        if len(self._messages) >= self.size:  # self.full
            self.lost += 1
            self.total_lost += 1
            return False
        if self.lost:  # DEM 4.2-2 "Stack: 1 = stack overflow with loss of at least one message"
            message = message.flagged()
            self.lost = 0
        self._messages.append(message)
        self.total_stored += 1
        return True

    def pop(self, count: int) -> list[Message]:
        """Remove and return up to ``count`` oldest messages (DEM 4.2-3: read = deleted)."""
        messages = self._messages
        popleft = messages.popleft
        return [popleft() for _ in range(min(count, len(messages)))]

    def peek(self) -> list[Message]:
        return list(self._messages)

    def purge(self) -> None:
        """DEM 4.2-1: "the messages are deleted and the stack is emptied"."""
        self._messages.clear()
        self.lost = 0
