"""The channel request tables (SCM 4.1-4.4): what to send, how many to receive, the time-out.

Tables are words with the 1st character in the low byte; time-outs are BCD on a
100 ms base, 0 meaning no time-out (AMB-SCM-16); the number of characters to
receive is binary.  A table that does not fit its request is answered H'FD'.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

from fieldtwin.clock import MS
from fieldtwin.tsx.scm.config import Refused
from fieldtwin.words import bytes_to_words, is_bcd

TIMEOUT_BASE_US = 100 * MS  # SCM 4.1 "a time base of 100 ms"
MAX_CHARS = 254  # SCM 4.1-4.4

# request codes (TXTi,C)
TX_TIMEOUT, TX_REPORT, TX_NO_REPORT, RX_TIMEOUT, RX, TXRX_TIMEOUT, TXRX, COMBINED = range(8)


class JobKind(enum.Enum):
    WRITE = "transmission"
    READ = "reception"
    WRITE_READ = "transmission/reception"


@dataclass(frozen=True, slots=True)
class Job:
    """A parsed request."""

    code: int
    kind: JobKind
    chars: bytes = b""
    count: int = 0
    timeout_us: int | None = None
    report: bool = True  # request 2 has none (AMB-SCM-10)

    @property
    def writes(self) -> bool:
        return self.kind is not JobKind.READ

    @property
    def reads(self) -> bool:
        return self.kind is not JobKind.WRITE


def _timeout(word: int) -> int | None:
    if not is_bcd(word):
        raise Refused(f"time-out {word:04X} is not BCD")  # SCM 4.5 "time not coded in BCD"
    value = int(f"{word:04X}")
    return value * TIMEOUT_BASE_US if value else None


def _count(word: int) -> int:
    if not 1 <= word <= MAX_CHARS:
        raise Refused(f"number of characters to receive {word} (allowed 1..{MAX_CHARS})")
    return word


def _need(data: bytes, ok: bool, what: str) -> None:
    if not ok:
        raise Refused(f"TXTi,L = {len(data)}: {what}")


def parse(code: int, data: bytes) -> Job:
    """A request code and its transmission table -> Job; Refused when they do not fit."""
    w = bytes_to_words(data[:4])
    n = len(data)
    if code == TX_TIMEOUT:
        _need(data, n >= 3, "at least 3 bytes (time-out + characters)")
        return Job(code, JobKind.WRITE, data[2:], timeout_us=_timeout(w[0]))
    if code in (TX_REPORT, TX_NO_REPORT):
        _need(data, n >= 1, "at least 1 character")
        return Job(code, JobKind.WRITE, data, report=code == TX_REPORT)
    if code == RX_TIMEOUT:
        _need(data, n == 4, "must be 4 (time-out + number of characters)")
        return Job(code, JobKind.READ, count=_count(w[1]), timeout_us=_timeout(w[0]))
    if code == RX:
        _need(data, n == 2, "must be 2 (number of characters)")
        return Job(code, JobKind.READ, count=_count(w[0]))
    if code == TXRX_TIMEOUT:  # AMB-SCM-12: [time-out, count, characters]
        _need(data, n >= 5, "at least 5 bytes")
        return Job(code, JobKind.WRITE_READ, data[4:], _count(w[1]), _timeout(w[0]))
    if code == TXRX:  # AMB-SCM-12: [count, characters]
        _need(data, n >= 3, "at least 3 bytes")
        return Job(code, JobKind.WRITE_READ, data[2:], _count(w[0]))
    if code == COMBINED:
        return _combined(data, w)
    raise Refused(f"unknown request code {code:02X}")


def _combined(data: bytes, w: list[int]) -> Job:
    # SCM 4.3 request 7: count 0 = write; count and L = 4 = read; count and L > 4 = write/read
    _need(data, len(data) >= 4, "at least 4 bytes (time-out + number of characters)")
    timeout = _timeout(w[0])
    if w[1] == 0:
        _need(data, len(data) > 4, "a write request needs characters")
        return Job(COMBINED, JobKind.WRITE, data[4:], timeout_us=timeout)
    if len(data) == 4:
        return Job(COMBINED, JobKind.READ, count=_count(w[1]), timeout_us=timeout)
    return Job(COMBINED, JobKind.WRITE_READ, data[4:], _count(w[1]), timeout)


def is_fd_write(code: int, data: bytes) -> bool:
    """A request 7 whose number of characters to receive is 0 (SCM 4.4 transmission table)."""
    return code == COMBINED and len(data) >= 4 and data[2] == 0 and data[3] == 0
