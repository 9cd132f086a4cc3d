"""A small table-backed SlaveDevice for the Modbus core tests (not the TES)."""

from __future__ import annotations

import collections
from dataclasses import dataclass, field

from fieldtwin.modbus.model import (
    Counter,
    ExceptionCode,
    Link,
    ReadBits,
    ReadExceptionStatus,
    ReadWords,
    Request,
    Result,
    WriteBit,
    WriteBits,
    WriteWord,
    WriteWords,
)

SIZE = 256


@dataclass
class TableDevice:
    """Words 0..255 (fc 03/04/06/10), coils 0..255 (fc 01/05/0F), inputs = coils (fc 02)."""

    slave: int
    delay_us: int = 0
    status: int = 0x5A
    not_ready: bool = False
    words: list[int] = field(default_factory=lambda: list(range(SIZE)))
    coils: list[bool] = field(default_factory=lambda: [False] * SIZE)
    counters: collections.Counter[tuple[Link, Counter]] = field(default_factory=collections.Counter)
    log: list[tuple[Request, bool, int]] = field(default_factory=list)

    def counted(self, counter: Counter, link: Link = Link.RS485) -> int:
        return self.counters[(link, counter)]

    def count(self, link: Link, counter: Counter, now: int) -> None:
        self.counters[(link, counter)] += 1

    def answer_delay(self, link: Link) -> int:
        return self.delay_us

    def execute(self, request: Request, link: Link, now: int, broadcast: bool) -> Result:
        self.log.append((request, broadcast, now))
        if self.not_ready:
            return ExceptionCode.SLAVE_DEVICE_FAILURE
        match request:
            case ReadExceptionStatus():
                return self.status
            case ReadBits(address=a, count=n) if a + n <= SIZE:
                return tuple(self.coils[a : a + n])
            case ReadWords(address=a, count=n) if a + n <= SIZE:
                return tuple(self.words[a : a + n])
            case WriteBit(address=a, value=v) if a < SIZE:
                self.coils[a] = v
                return None
            case WriteWord(address=a, value=v) if a < SIZE:
                self.words[a] = v
                return None
            case WriteBits(address=a, values=vs) if a + len(vs) <= SIZE:
                self.coils[a : a + len(vs)] = vs
                return None
            case WriteWords(address=a, values=vs) if a + len(vs) <= SIZE:
                self.words[a : a + len(vs)] = vs
                return None
        return ExceptionCode.ILLEGAL_DATA_ADDRESS
