"""The DEM 24 Text Block requests (DEM 4.4 request code list).

| request            | C    | M      | V      | written | read      |
|--------------------|------|--------|--------|---------|-----------|
| logging read       | 1    | xy00   | 81/FD  | 4       | 234 max   |
| time write         | 2    | xy00   | FE/FD  | 8       | 0         |
| configuration write| 40   | xy63   | FE/FD  | 18      | 0 (STOP)  |
| configuration read | 41   | xy63   | 71/FD  | 0       | 18        |

H'0F', H'47', H'49', H'4A' are the common requests of the base module.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

from fieldtwin.tsx.dem24.config import (
    CONFIG_BYTES,
    FB_TIME_REFUSED,
    Dem24Config,
    Refusal,
    check_config,
)
from fieldtwin.tsx.dem24.logbook import Logbook
from fieldtwin.tsx.dem24.stack import MESSAGE_BYTES, READ_MAX, Message
from fieldtwin.tsx.dem24.timebase import TimeReference
from fieldtwin.tsx.textblock import MODULE_SYSTEM, V_ERROR, V_OK_WRITE, Answer, Exchange
from fieldtwin.words import bytes_to_words, words_to_bytes


class Dem24(Protocol):
    """What the requests use of the module (fieldtwin.tsx.dem24.module.Dem24)."""

    config: Dem24Config
    logbook: Logbook

    @property
    def running(self) -> bool: ...

    def read_messages(self, count: int) -> list[Message]: ...

    def set_fault(self, bit: int, active: bool) -> None: ...

    def refresh_status(self) -> None: ...

    def refuse_config(self, diag_word: int) -> None: ...

    def apply_config(self, config: Dem24Config, now: int) -> None: ...


REQ_READ = 0x01
REQ_TIME = 0x02
REQ_CONFIG_WRITE = 0x40
REQ_CONFIG_READ = 0x41
V_READ = 0x81
V_CONFIG = 0x71
CHANNEL_0 = 0x00


def handle(mod: Dem24, exchange: Exchange, now: int) -> None:
    request = exchange.request
    handler = _HANDLERS.get((request.channel, request.code))
    answer = (
        Answer(v=V_ERROR)
        if handler is None
        else handler(mod, exchange.request.data, now, request.capacity)
    )
    exchange.complete(answer, now)


def read_log(mod: Dem24, data: bytes, now: int, capacity: int) -> Answer:
    """DEM 4.2-3: exchange number and count in; 26 bytes per message out, oldest first."""
    if len(data) < 4:
        return Answer(v=V_ERROR)
    exchange_number, wanted = bytes_to_words(data[:4])
    if wanted < 1:
        return Answer(v=V_ERROR)
    # AMB-DEM-12: at most 9, at most what the reception table holds (nothing is lost)
    count = min(wanted, READ_MAX, capacity // MESSAGE_BYTES)
    messages = mod.read_messages(count)
    if not messages:  # "the module returns the exchange number and zero": TXTi,S = 2
        return Answer(v=V_READ, data=words_to_bytes([exchange_number & 0xFF]))
    words: list[int] = []
    for message in messages:
        words.extend(message.words(exchange_number, len(messages)))
    return Answer(v=V_READ, data=words_to_bytes(words))


def write_time(mod: Dem24, data: bytes, now: int, capacity: int) -> Answer:
    """DEM 4.1-2: 8 bytes; refused -> H'FD' and fault bit 34 (time reference refused)."""
    ref = TimeReference.decode(data)
    if ref is None:
        mod.set_fault(FB_TIME_REFUSED, True)
        return Answer(v=V_ERROR)
    mod.set_fault(FB_TIME_REFUSED, False)
    mod.logbook.reference(ref, now)  # taken at the next pulse (4.1-3)
    mod.refresh_status()
    return Answer(v=V_OK_WRITE)


def write_config(mod: Dem24, data: bytes, now: int, capacity: int) -> Answer:
    """DEM 3.4-2/3.4-3: 18 bytes in STOP; refusals set IWxy,0,B and IWxy,2,1..5."""
    if mod.running:
        return Answer(v=V_ERROR)  # AMB-DEM-18: refused, the configuration in force is kept
    if len(data) != CONFIG_BYTES:
        mod.refuse_config(0)
        return Answer(v=V_ERROR)
    result = check_config(bytes_to_words(data))
    if isinstance(result, Refusal):
        mod.refuse_config(result.diag_word)
        return Answer(v=V_ERROR)
    mod.apply_config(result, now)
    return Answer(v=V_OK_WRITE)


def read_config(mod: Dem24, data: bytes, now: int, capacity: int) -> Answer:
    """DEM 4.4: 18 bytes, V = H'71'."""
    return Answer(v=V_CONFIG, data=mod.config.to_bytes())


_Handler = Callable[["Dem24", bytes, int, int], Answer]
_HANDLERS: dict[tuple[int, int], _Handler] = {
    (CHANNEL_0, REQ_READ): read_log,
    (CHANNEL_0, REQ_TIME): write_time,
    (MODULE_SYSTEM, REQ_CONFIG_WRITE): write_config,
    (MODULE_SYSTEM, REQ_CONFIG_READ): read_config,
}
