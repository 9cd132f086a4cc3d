"""The device side of §7: execute decoded Modbus requests against the memory map.

Bit addresses are word x 16 + bit (§7.1.2); fc 04 reads the same memory as 03
(AMB-TES-04); broadcast writes run with no reply (§7.2.6), broadcast reads are
ignored (AMB-TES-29).  Exception 1: unknown function, 2: a bad address or
quantity (AMB-TES-01), 4: "slave not ready" in the 32-bit area (§6.2.3.2,
§6.4.13; AMB-TES-28).

``SlaveAdapter`` is the Modbus side of a TES: it owns nothing but what it is
given (the register file, the RAM, the line faults and the TES's
``master_request``), so a master read from Python (``Tes.read``) and one from
the wire take the same path.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import TypeVar

from fieldtwin.clock import MS
from fieldtwin.modbus.model import (
    NO_REPLY,
    Counter,
    ExceptionCode,
    Link,
    ReadBits,
    ReadExceptionStatus,
    ReadWords,
    Request,
    Result,
    WriteBit,
    WriteWord,
    WriteWords,
)
from fieldtwin.modbus.slave import _counter_for
from fieldtwin.tes import state
from fieldtwin.tes.access import ReadPlan, RegisterFile, WritePlan
from fieldtwin.tes.digital import TICK
from fieldtwin.tes.faults import LineFaults
from fieldtwin.tes.memmap import Register, coherent_from

NOT_READY = ExceptionCode.SLAVE_DEVICE_FAILURE  # code 4, "slave not ready"
_RS232 = Link.RS232
# the counters' slots (state.COUNTER_ORDER) a fused exchange bumps itself
_GOOD = state.COUNTER_ORDER.index(Counter.GOOD_FRAMES)
_EXECUTED = state.COUNTER_ORDER.index(Counter.FRAMES_EXECUTED)
BAD_ADDRESS = ExceptionCode.ILLEGAL_DATA_ADDRESS
_READS = (ReadBits, ReadWords, ReadExceptionStatus)
SPAN_CACHE = 64  # spans remembered per TES (the map is fixed per model)
K = TypeVar("K")
V = TypeVar("V")
# a word-read span's registers, read plan, and whether it may answer "not ready"
_Planned = tuple[Sequence[Register], ReadPlan, bool]
_NO_SPAN: _Planned = ((), lambda now: (), False)
_WritePlanned = tuple[Sequence[Register], WritePlan, bool]
_NO_WRITE_SPAN: _WritePlanned = ((), lambda values, now: None, False)


def _kept(cache: dict[K, V], key: K, value: V) -> V:
    """``value``, kept in ``cache`` under ``key``; the cache emptied first when it holds
    SPAN_CACHE (bounded: a master polls a few spans over and over)."""
    if len(cache) >= SPAN_CACHE:
        cache.clear()
    cache[key] = value
    return value


def _span_of(
    table: Mapping[int, Register], first: int, count: int, writing: bool
) -> tuple[Register, ...] | None:
    regs = [table.get(a) for a in range(first, first + count)]
    if any(r is None or (writing and not r.access.writable) for r in regs):
        return None
    return tuple(r for r in regs if r is not None)


class SlaveAdapter:
    """Executes decoded Modbus requests against one TES's register file.

    ``planned`` (True): a word read runs the span's read plan (``RegisterFile.plan``,
    built at the span's first read and kept); False: ``get_words``, word by word (the
    reference, tests/tes/test_read_plan.py).
    """

    planned = True

    def __init__(
        self,
        registers: RegisterFile,
        ram: state.Ram,
        faults: LineFaults,
        master_request: Callable[[Link, int], None],
    ) -> None:
        self.registers = registers
        self.model = registers.model
        self._ram = ram
        self._faults = faults
        self._master_request = master_request
        self._coherent_from = coherent_from(self.model)
        # (first, count, writing) -> the registers of a valid span, or None
        self._spans: dict[tuple[int, int, bool], tuple[Register, ...] | None] = {}
        # first * 128 + count -> (registers, read plan, may answer "not ready") of a
        # word-read span (_NO_SPAN: not a valid one)
        self._plans: dict[int, _Planned] = {}
        self._write_plans: dict[int, _WritePlanned] = {}  # the same for word writes
        self._analog = self.model.is_analog

    # --- SlaveDevice -------------------------------------------------------

    def execute(self, request: Request, link: Link, now: int, broadcast: bool) -> Result:
        """Carry out one request; None for a write that worked or a broadcast."""
        if not self._ram.powered or self._faults.no_answer:
            return NO_REPLY  # a TES without 24 V (or deaf) does not answer
        self.begin_exchange(link, now)
        if broadcast and isinstance(request, _READS):
            result: Result = None
        else:
            result = self._run(request, link, now)
        self.end_exchange()
        return None if broadcast else result

    def exchange(self, request: Request, link: Link, now: int) -> tuple[Result, int] | None:
        """A request to this TES from a TCP session, bookkeeping and all, in one call:
        what the session's ``count`` (a good frame), ``execute``, ``count`` (the reply's
        counter) and ``answer_delay`` do, in that order; the result and the instant the
        reply leaves, or None when the TES stays silent (nothing counted but the frame)."""
        ram = self._ram
        counters = ram.counters["rs232" if link is _RS232 else "rs485"]
        values = counters.values
        values[_GOOD] = (values[_GOOD] + 1) & 0xFFFF  # bump(GOOD_FRAMES)
        if not ram.powered or self._faults.no_answer:
            return None
        self._master_request(link, now)
        if request.__class__ is ReadWords:  # the usual request: no dispatch
            result = self._read_words(request, link, now)
        else:
            result = self._run(request, link, now)
        if self._analog:
            ram.status &= ~(state.POWER_ON | state.FALLBACK)  # end_exchange
        if result.__class__ is tuple or result is None:
            values[_EXECUTED] = (values[_EXECUTED] + 1) & 0xFFFF  # bump(FRAMES_EXECUTED)
        else:
            counters.bump(_counter_for(result))
        key = state.RS232_DELAY if link is _RS232 else state.RS485_DELAY
        delay = ram.params[key]
        assert isinstance(delay, int)
        return result, now + delay * MS + self._faults.late_us

    def begin_exchange(self, link: Link, now: int) -> None:
        self._master_request(link, now)

    def end_exchange(self) -> None:
        if self.model.is_analog:
            self._ram.status &= ~(state.POWER_ON | state.FALLBACK)  # §6.4.1 first exchange

    def _run(self, request: Request, link: Link, now: int) -> Result:
        if request.__class__ is ReadWords:  # the usual request first, by its class
            return self._read_words(request, link, now)
        if isinstance(request, ReadExceptionStatus):
            return self.registers.status_word() & 0xFF  # §7.2.6 the 8 low bits of the status word
        if isinstance(request, ReadWords):
            return self._read_words(request, link, now)
        if isinstance(request, ReadBits):
            return self._read_bits(request, link, now)
        if isinstance(request, WriteWord):
            return self._write_words(request.address, (request.value,), link, now)
        if isinstance(request, WriteWords):
            return self._write_words(request.address, request.values, link, now)
        if isinstance(request, WriteBit):
            return self._write_bits(request.address, (request.value,), link, now)
        return self._write_bits(request.address, request.values, link, now)

    def _span(self, first: int, count: int, limit: int, writing: bool) -> Sequence[Register] | None:
        if not 1 <= count <= limit:
            return None
        key = (first, count, writing)
        spans = self._spans
        regs = spans.get(key)
        if regs is None:
            regs = _kept(spans, key, _span_of(self.registers.table, first, count, writing))
        return regs

    def _busy(self, regs: Sequence[Register], link: Link, now: int) -> bool:
        if regs[-1].address < self._coherent_from:
            return False
        faults = self._faults
        window_us = faults.not_ready_window_us
        window = bool(window_us) and (now - self._ram.booted_at) % TICK < window_us
        if not faults.not_ready(window):
            return False
        self._ram.counters[state.link_key(link)].not_ready_owed = True
        return True

    def _planned(self, first: int, count: int) -> _Planned:
        """The read plan of a word-read span (no registers: not a valid span), built at
        the span's first read and kept: it depends on nothing but the model."""
        regs = self._span(first, count, 125, writing=False)
        planned = _NO_SPAN
        if regs is not None:
            late = regs[-1].address >= self._coherent_from
            planned = (regs, self.registers.plan(regs), late)
        return _kept(self._plans, first * 128 + count, planned)

    def _write_planned(self, first: int, count: int) -> _WritePlanned:
        """The write plan of a word-write span (no registers: not a valid span)."""
        regs = self._span(first, count, 123, writing=True)
        planned = _NO_WRITE_SPAN
        if regs is not None:
            late = regs[-1].address >= self._coherent_from
            planned = (regs, self.registers.write_plan(regs), late)
        return _kept(self._write_plans, first * 128 + count, planned)

    def _read_words(self, request: ReadWords, link: Link, now: int) -> Result:
        if request.function not in (3, 4):
            return ExceptionCode.ILLEGAL_FUNCTION
        if self.planned and 1 <= request.count <= 125:
            planned = self._plans.get(request.address * 128 + request.count)
            if planned is None:
                planned = self._planned(request.address, request.count)
            span, plan, late = planned
            if not span:
                return BAD_ADDRESS
            if late and self._busy(span, link, now):
                return NOT_READY
            return plan(now)
        regs = self._span(request.address, request.count, 125, writing=False)
        if regs is None:
            return BAD_ADDRESS
        if self._busy(regs, link, now):
            return NOT_READY
        return self.registers.get_words(regs, now)

    def _read_bits(self, request: ReadBits, link: Link, now: int) -> Result:
        if request.function not in (1, 2):
            return ExceptionCode.ILLEGAL_FUNCTION
        if not 1 <= request.count <= 2000:
            return BAD_ADDRESS
        first, last = request.address >> 4, (request.address + request.count - 1) >> 4
        regs = self._span(first, last - first + 1, 2000, writing=False)
        if regs is None:
            return BAD_ADDRESS
        if self._busy(regs, link, now):
            return NOT_READY
        words = {r.address: self.registers.get(r, now) for r in regs}
        bits = range(request.address, request.address + request.count)
        return tuple(bool((words[b >> 4] >> (b & 0xF)) & 1) for b in bits)

    def _write_words(self, first: int, values: tuple[int, ...], link: Link, now: int) -> Result:
        count = len(values)
        if self.planned and 1 <= count <= 123:
            planned = self._write_plans.get(first * 128 + count)
            if planned is None:
                planned = self._write_planned(first, count)
            span, plan, late = planned
            if not span:
                return BAD_ADDRESS
            if late and self._busy(span, link, now):
                return NOT_READY
            plan(values, now)
            return None
        regs = self._span(first, len(values), 123, writing=True)
        if regs is None:
            return BAD_ADDRESS
        if self._busy(regs, link, now):
            return NOT_READY
        self.registers.put_words(regs, [value & 0xFFFF for value in values], now)
        return None

    def _write_bits(self, first: int, values: tuple[bool, ...], link: Link, now: int) -> Result:
        if not 1 <= len(values) <= 1968:
            return BAD_ADDRESS
        lo, hi = first >> 4, (first + len(values) - 1) >> 4
        regs = self._span(lo, hi - lo + 1, 1968, writing=True)
        if regs is None:
            return BAD_ADDRESS
        if self._busy(regs, link, now):
            return NOT_READY
        words = {r.address: self.registers.peek(r, now) for r in regs}
        for offset, value in enumerate(values):
            bit = first + offset
            mask = 1 << (bit & 0xF)
            words[bit >> 4] = (words[bit >> 4] | mask) if value else (words[bit >> 4] & ~mask)
        for reg in regs:
            self.registers.put(reg, words[reg.address], now)
        return None
