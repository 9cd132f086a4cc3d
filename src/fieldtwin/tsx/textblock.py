"""The CPL Text Block: what the PLC and a module exchange through the message interface.

A request is a code (TXTi,C), an address (TXTi,M = H'xyzz'), the bytes sent
(TXTi,L of the transmission table) and a reception capacity.  The answer is a
report (TXTi,V, or TXTi,R on a TSX 47-20), the bytes received (TXTi,S) and the
data.  A system error ends the exchange with TXTi,E = 1 and an error code in
TXTi,S (SCM 4.5 "Status word TXTi,S").
"""

from __future__ import annotations

import enum
from collections.abc import Callable
from dataclasses import dataclass

from fieldtwin.errors import ProtocolError
from fieldtwin.words import bytes_to_words

# SCM 4.5: the TXTi,S error codes at the end of an incorrect exchange (TXTi,E = 1)
ERR_CANCELLED = 1  # exchange in progress cancelled by reset
ERR_TABLE_LENGTH = 2  # transmission table length error
ERR_POWER_BREAK = 3  # power break during the exchange
ERR_MODULE_FAULT = 4  # module fault
ERR_PARAMETER = 5  # parameter error or too many active Text Blocks
ERR_TOO_LONG = 6  # message received longer than planned
ERR_INDIRECT = 10  # incorrect addressing with an indirect Text Block

ERROR_TEXT = {
    ERR_CANCELLED: "exchange in progress cancelled by reset",
    ERR_TABLE_LENGTH: "transmission table length error",
    ERR_POWER_BREAK: "power break during the exchange",
    ERR_MODULE_FAULT: "module fault",
    ERR_PARAMETER: "parameter error or too many active Text Blocks",
    ERR_TOO_LONG: "message received longer than planned",
    ERR_INDIRECT: "incorrect addressing with an indirect Text Block",
}

# Reports every module shares
V_OK_WRITE = 0xFE  # write acknowledged
V_ERROR = 0xFD  # incorrect exchange

MODULE_SYSTEM = 0x63  # TXTi,M = H'xy63': the module system, not a channel


@dataclass(frozen=True, slots=True)
class Request:
    """One Text Block request as the module receives it."""

    code: int  # TXTi,C
    channel: int  # zz of TXTi,M: 0x00, 0x01 ... or MODULE_SYSTEM (0x63)
    data: bytes  # the TXTi,L bytes of the transmission table
    capacity: int  # reception table length in bytes

    @property
    def words(self) -> list[int]:
        return bytes_to_words(self.data)


@dataclass(frozen=True, slots=True)
class Answer:
    """The module's answer: report V, the data (S = len(data)), or a system error."""

    v: int = 0
    data: bytes = b""
    error: int | None = None  # a TXTi,S error code: E = 1, S = error

    @staticmethod
    def fault(code: int) -> Answer:
        return Answer(v=0, data=b"", error=code)


class ExchangeState(enum.Enum):
    PENDING = "pending"  # held by the module (waiting for Run, characters, a time-out...)
    DONE = "done"


class Exchange:
    """A request inside a module, until the module completes it exactly once."""

    __slots__ = ("_on_done", "answer", "request", "started_at", "state")

    def __init__(
        self, request: Request, started_at: int, on_done: Callable[[Exchange, int], None]
    ) -> None:
        self.request = request
        self.started_at = started_at
        self.state = ExchangeState.PENDING
        self.answer: Answer | None = None
        self._on_done = on_done

    @property
    def done(self) -> bool:
        return self.state is ExchangeState.DONE

    def complete(self, answer: Answer, now: int) -> None:
        """End the exchange; a second completion is a ProtocolError (it would hide a
        module answering an exchange that is already over)."""
        if self.state is ExchangeState.DONE:
            raise ProtocolError(
                f"exchange C={self.request.code:02X} channel {self.request.channel:02X}:"
                f" can't complete it twice (first answer {self.answer})"
            )
        self.state = ExchangeState.DONE
        self.answer = answer
        self._on_done(self, now)
