"""The Text Blocks of a PLC: inputs M, C, L and the tables; outputs D, E, V/R, S.

A Text Block started during a cycle is validated at the end of the master task
(AEM 4.2-2), handed to the module, and its report appears at the end of the first
cycle that ends after the module's answer (docs/manual-notes.md F-5).  System
errors end it with TXTi,E = 1 and a TXTi,S code (SCM 4.5).
"""

from __future__ import annotations

import enum
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from fieldtwin.clock import S
from fieldtwin.errors import ConfigError, FieldtwinError
from fieldtwin.fsm import Machine, Table
from fieldtwin.objects import DATA_WORDS as DATA_WORDS  # the PL7 name, in the kernel
from fieldtwin.tsx.bus import ModuleState
from fieldtwin.tsx.textblock import (
    ERR_CANCELLED,
    ERR_INDIRECT,
    ERR_MODULE_FAULT,
    ERR_PARAMETER,
    ERR_TABLE_LENGTH,
    ERR_TOO_LONG,
    ERROR_TEXT,
    MODULE_SYSTEM,
    Answer,
    Exchange,
    Request,
)
from fieldtwin.words import bytes_to_words, format_hex, to_signed, words_to_bytes

if TYPE_CHECKING:
    from fieldtwin.tsx.module import IntelligentModule

# AEM 3.5-1 configuration screen "NUMBER OF TEXT BLOCKS N/MAX : 4 /64": TXT0..TXT63
TEXT_BLOCKS = 64

# M -> (module, present in its slot), or None for an empty slot
Lookup = Callable[[int], "tuple[IntelligentModule, bool] | None"]


class ExchangeTimeout(FieldtwinError):
    """plc.exchange gave up: the module did not end the exchange within the bound."""


@dataclass(frozen=True, slots=True)
class ExchangeResult:
    """The outputs of a Text Block at the end of an exchange."""

    v: int  # the report (TXTi,V, or TXTi,R on a 47-20)
    s: int  # bytes received, or the error code when e
    e: bool  # TXTi,E: incorrect exchange
    data: bytes
    report_name: str = "V"
    ended_at_us: int = 0  # simulated microseconds when the report was set

    @property
    def ended_at(self) -> float:
        """Simulated seconds when the report was set (the end of a PLC cycle)."""
        return self.ended_at_us / S

    @property
    def r(self) -> int:
        return self.v

    @property
    def d(self) -> bool:
        return True

    @property
    def words(self) -> list[int]:
        return bytes_to_words(self.data)

    @property
    def signed_words(self) -> list[int]:
        """The received words as signed 16-bit integers (measurements below 0)."""
        return [to_signed(w) for w in self.words]

    @property
    def error_text(self) -> str | None:
        return ERROR_TEXT.get(self.s, f"error {self.s}") if self.e else None

    def __str__(self) -> str:
        head = f"TXT,{self.report_name} = {format_hex(self.v)}  TXT,S = {self.s}"
        if self.e:
            return f"{head}  TXT,E = 1 ({self.error_text})"
        words = " ".join(format_hex(w) for w in self.words)
        return f"{head}  TXT,E = 0" + (f"  data = {words}" if words else "")


class TxtState(enum.Enum):
    IDLE = "idle"
    STARTED = "started"  # waiting for the end of the master task
    IN_MODULE = "in module"
    ANSWERED = "answered"  # report shown at the end of the next cycle
    DONE = "done"


class TxtInput(enum.Enum):
    START = "start"  # the program set the inputs and started the block
    REFUSE = "refuse"  # validation ended it with a system error (TXTi,S = 2, 4, 5, 10)
    SUBMIT = "submit"  # validated at the end of the master task, handed to the module
    ANSWER = "answer"  # the module answered (or ended the exchange)
    REPORT = "report"  # outputs D, E, V/R, S set at the end of a cycle
    END = "end"  # reset, power break, cold restart, module pulled: ended at once


@dataclass(slots=True)
class TextBlock:
    """A CPL Text Block: inputs M, C, L and the tables; outputs D, E, V/R, S.

    It is also the handle ``plc.start_exchange`` returns: ``done`` (TXTi,D),
    ``result`` (the :class:`ExchangeResult`, None before the end) and ``ended_at``
    (simulated seconds when it ended, None before).
    """

    index: int
    m: int = 0
    c: int = 0
    send: bytes = b""
    capacity: int = 0
    answer: Answer | None = None
    answered_at_us: int = 0
    result: ExchangeResult | None = None
    exchange: Exchange | None = field(default=None, repr=False)
    ticket: object = field(default=None, repr=False)
    table: int | None = None
    indirect: int | None = None
    recv_table: int | None = None
    machine: Machine[TxtState, TxtInput, TextBlock] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self.machine = Machine(TXT, TxtState.IDLE, self)

    @property
    def state(self) -> TxtState:
        return self.machine.state

    @property
    def done(self) -> bool:
        return self.state is TxtState.DONE

    @property
    def ended_at(self) -> float | None:
        """Simulated seconds when the exchange ended (its report set), None before."""
        return None if self.result is None else self.result.ended_at

    def _answered(self, answer: Answer, at: int) -> None:
        self.answer, self.answered_at_us = answer, at


# The Text Block machine: every state change of a TextBlock is one of these pairs.
TXT: Table[TxtState, TxtInput] = Table(
    "text block",
    TxtState,
    TxtInput,
    {
        (TxtState.IDLE, TxtInput.START): (None, TxtState.STARTED),
        (TxtState.DONE, TxtInput.START): (None, TxtState.STARTED),
        (TxtState.STARTED, TxtInput.REFUSE): (TextBlock._answered, TxtState.ANSWERED),
        (TxtState.STARTED, TxtInput.SUBMIT): (None, TxtState.IN_MODULE),
        (TxtState.IN_MODULE, TxtInput.ANSWER): (TextBlock._answered, TxtState.ANSWERED),
        (TxtState.ANSWERED, TxtInput.REPORT): (None, TxtState.DONE),
        (TxtState.STARTED, TxtInput.END): (None, TxtState.DONE),
        (TxtState.IN_MODULE, TxtInput.END): (None, TxtState.DONE),
        (TxtState.ANSWERED, TxtInput.END): (None, TxtState.DONE),
    },
)


_BUSY = (TxtState.STARTED, TxtState.IN_MODULE, TxtState.ANSWERED)
_WORK = (TxtState.STARTED, TxtState.ANSWERED)  # what the end of a master task acts on


class TextBlocks:
    """Every Text Block of one PLC, and the internal words their tables live in."""

    def __init__(self, table_max: int, report_name: str, lookup: Lookup) -> None:
        self.table_max = table_max
        self.report_name = report_name
        self.data = [0] * DATA_WORDS
        self._lookup = lookup
        self._txts: dict[int, TextBlock] = {}

    def block(self, index: int) -> TextBlock:
        if isinstance(index, bool) or not isinstance(index, int) or not 0 <= index < TEXT_BLOCKS:
            raise ConfigError(
                f"TXT{index}: no such Text Block (allowed TXT0..TXT{TEXT_BLOCKS - 1},"
                f" a PLC has at most {TEXT_BLOCKS})"
            )
        found = self._txts.get(index)
        if found is None:
            found = self._txts[index] = TextBlock(index)
        return found

    def busy(self) -> bool:
        """A Text Block is started, in a module or answered (not idle nor done)."""
        return any(tb.machine.state in _BUSY for tb in self._txts.values())

    def end_of_task(self, now: int, running: bool) -> None:
        """Report the answers that came in, then validate the new requests."""
        txts = self._txts.values()
        for tb in txts:
            if tb.machine.state in _WORK:
                break
        else:
            return  # nothing to report or validate: an idle task costs one look
        for tb in txts:
            if tb.state is TxtState.ANSWERED and tb.answered_at_us < now:
                self._finish(tb, TxtInput.REPORT, now)
        if running:
            for tb in txts:
                if tb.state is TxtState.STARTED:
                    self._validate(tb, now)

    def end_all(self, code: int, now: int, where: tuple[int, int] | None = None) -> None:
        """End every exchange in progress (power break, cold restart), or those
        addressed to one (rack, slot) (the module pulled out): TXTi,E = 1, TXTi,S = code."""
        for tb in self._txts.values():
            if tb.state in _BUSY and (where is None or _slot_of(tb.m) == where):
                self._end(tb, Answer.fault(code), now)

    def _end(self, tb: TextBlock, answer: Answer, now: int) -> None:
        """End ``tb`` with ``answer``; the module forgets the exchange too, so that its
        channel takes the next one (else TXTi,S = 5 "too many active" for ever)."""
        tb.ticket = None
        if tb.state is TxtState.IN_MODULE and tb.exchange is not None:
            found = self._lookup(tb.m)
            if found is not None and not tb.exchange.done:
                found[0].cancel_exchange(tb.exchange, now)
        tb.answer = answer
        self._finish(tb, TxtInput.END, now)

    def start(
        self,
        m: int,
        c: int,
        send: Sequence[int] | None = None,
        *,
        send_bytes: bytes | None = None,
        length: int | None = None,
        recv_bytes: int = 0,
        txt: int = 0,
        table: int | None = None,
        indirect: int | None = None,
        recv_table: int | None = None,
    ) -> TextBlock:
        """Set a Text Block's inputs and start it; it is validated at the end of the task.

        ``send``/``send_bytes`` give the transmission table directly; or ``table``
        names it in the internal words (W100 -> 100, direct addressing) or
        ``indirect`` names a word that holds the table's address.  The received
        words go to ``recv_table`` (W1000 -> 1000) when given, else to the table.
        """
        _check_arguments(txt, recv_bytes, (table, recv_table, indirect))
        tb = self.block(txt)
        if tb.state in _BUSY:
            raise ConfigError(
                f"TXT{txt} is busy ({tb.state.value}); reset it or wait for TXT{txt},D"
            )
        tb.table, tb.indirect, tb.recv_table = table, indirect, recv_table
        if send is None and send_bytes is None and (table is not None or indirect is not None):
            send = self._table_words(table, indirect, length)
        data = send_bytes if send_bytes is not None else words_to_bytes(send or [])
        unresolved = indirect is not None and self._resolve_table(None, indirect) is None
        if length is not None and not unresolved:  # else TXTi,S = 10 at validation
            if not 0 <= length <= len(data):
                raise ConfigError(f"TXT{txt},L = {length} but the table holds {len(data)} bytes")
            data = data[:length]
        tb.m, tb.c, tb.send, tb.capacity = m & 0xFFFF, c & 0xFF, data, recv_bytes
        tb.answer, tb.result, tb.exchange = None, None, None
        tb.machine.fire(TxtInput.START)
        return tb

    def _table_words(
        self, table: int | None, indirect: int | None, length: int | None
    ) -> list[int]:
        start = self._resolve_table(table, indirect)
        if start is None:
            return []
        count = (length or 0) + 1 >> 1
        return self.data[start : start + count]

    def _resolve_table(self, table: int | None, indirect: int | None) -> int | None:
        if indirect is not None:
            address = self.data[indirect]
            return address if address < DATA_WORDS else None
        return table

    def reset(self, txt: int, now: int) -> None:
        """The Text Block's R input: the exchange in progress ends with TXTi,S = 1."""
        tb = self.block(txt)
        if tb.state in _BUSY:
            self._end(tb, Answer.fault(ERR_CANCELLED), now)

    def _validate(self, tb: TextBlock, now: int) -> None:
        refusal = self._refusal(tb)
        if refusal is not None:
            tb.machine.fire(TxtInput.REFUSE, Answer.fault(refusal), now)
            return
        found = self._lookup(tb.m)
        assert found is not None
        module = found[0]
        tb.machine.fire(TxtInput.SUBMIT)
        ticket = tb.ticket = object()

        def done(exchange: Exchange, at: int) -> None:
            if tb.ticket is ticket and tb.state is TxtState.IN_MODULE:
                assert exchange.answer is not None
                tb.machine.fire(TxtInput.ANSWER, exchange.answer, at)

        request = Request(tb.c, tb.m & 0xFF, tb.send, tb.capacity)
        tb.exchange = module.submit(request, now, done)

    def _refusal(self, tb: TextBlock) -> int | None:
        """The system error that ends ``tb`` at validation (SCM 4.5), None if it goes."""
        if tb.indirect is not None and self._resolve_table(None, tb.indirect) is None:
            return ERR_INDIRECT
        if len(tb.send) > self.table_max or tb.capacity > self.table_max:
            return ERR_TABLE_LENGTH
        found = self._lookup(tb.m)
        if found is None or tb.m & 0xFF not in (0x00, 0x01, MODULE_SYSTEM):
            return ERR_PARAMETER
        if not found[1] or found[0].state is ModuleState.OFF:
            return ERR_MODULE_FAULT
        return None

    def _finish(self, tb: TextBlock, event: TxtInput, now: int) -> None:
        answer = tb.answer or Answer.fault(ERR_MODULE_FAULT)
        name = self.report_name
        if answer.error is not None:
            result = ExchangeResult(0, answer.error, True, b"", name, now)
        elif len(answer.data) > tb.capacity:
            result = ExchangeResult(answer.v, ERR_TOO_LONG, True, b"", name, now)
        else:
            result = ExchangeResult(answer.v, len(answer.data), False, answer.data, name, now)
            start = tb.recv_table
            if start is None:
                start = self._resolve_table(tb.table, tb.indirect)
            words = result.words
            if start is not None and words:
                end = min(start + len(words), DATA_WORDS)
                self.data[start:end] = words[: end - start]
        tb.result = result
        tb.machine.fire(event)


def _slot_of(m: int) -> tuple[int, int]:
    return (m >> 12) & 0xF, (m >> 8) & 0xF


def _check_arguments(txt: int, recv_bytes: int, tables: tuple[int | None, ...]) -> None:
    if txt < 0:
        raise ConfigError(f"TXT{txt}: a Text Block number cannot be negative")
    if recv_bytes < 0:
        raise ConfigError(f"reception capacity {recv_bytes} not allowed (allowed 0 or more bytes)")
    for given in tables:
        if given is not None and not 0 <= given < DATA_WORDS:
            raise ConfigError(f"table W{given} out of range (allowed W0..W{DATA_WORDS - 1})")
