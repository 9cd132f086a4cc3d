"""The PLC: models, racks and slots, the master task and its bus refresh, Text Blocks.

Each master-task cycle ends by refreshing the I/O bus: the PLC reads the modules'
input bits and words into its image and writes its output image to them
(register words every cycle, or every second cycle on a TSX 47-20: AEM 2.4-3).
A Text Block is validated at the end of the master task (AEM 4.2-2 "the request
is validated at the end of the master task when the outputs are updated") and
its report appears at the end of a later cycle.
"""

from __future__ import annotations

import enum
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from fieldtwin.clock import MS, Handle, SimClock, seconds
from fieldtwin.errors import ConfigError, FieldtwinError
from fieldtwin.tsx import registry
from fieldtwin.tsx.addressing import ObjectKind, ObjectRef, parse_object
from fieldtwin.tsx.module import BusImage, IntelligentModule, ModuleContext, ModuleState
from fieldtwin.tsx.textblock import (
    ERR_CANCELLED,
    ERR_INDIRECT,
    ERR_MODULE_FAULT,
    ERR_PARAMETER,
    ERR_POWER_BREAK,
    ERR_TABLE_LENGTH,
    ERR_TOO_LONG,
    ERROR_TEXT,
    MODULE_SYSTEM,
    Answer,
    Exchange,
    Request,
)
from fieldtwin.words import (
    bytes_to_words,
    format_hex,
    get_bit,
    set_bit,
    to_unsigned,
    words_to_bytes,
)


@dataclass(frozen=True, slots=True)
class PlcModel:
    name: str
    register_every: int  # register words refreshed every N cycles (AEM 2.4-3)
    table_max: int  # Text Block table length in bytes (SCM 4.1: 30 on a 47-20)
    report_name: str  # TXTi,R on a TSX 47-20, TXTi,V elsewhere (SCM 3.3)
    racks: int
    intelligent_slots: int  # slots of a rack that take intelligent modules
    basic_rack_max: int = 8  # intelligent modules in the basic rack (AEM 6.1-1)


MODELS = {
    "TSX 47-20": PlcModel("TSX 47-20", 2, 30, "R", 1, 4),
    # AEM 6.1-1: a single-rack basic configuration takes 5 intelligent modules at most
    "TSX 47-30": PlcModel("TSX 47-30", 1, 254, "V", 8, 8, 5),
    "TSX 67": PlcModel("TSX 67", 1, 254, "V", 8, 8),
    "TSX 87": PlcModel("TSX 87", 1, 254, "V", 8, 8),
}

POWER_RESERVE_US = 10 * MS
DATA_WORDS = 4096  # internal words W0..W4095 (Text Block tables, manual-notes)
_W_RE = re.compile(
    r"^W(\d{1,5})$", re.IGNORECASE
)  # a shorter break does not restart the modules (manual-notes)


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
    ended_at: int = 0

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


@dataclass(slots=True)
class TextBlock:
    """A CPL Text Block: inputs M, C, L and the tables; outputs D, E, V/R, S."""

    index: int
    m: int = 0
    c: int = 0
    send: bytes = b""
    capacity: int = 0
    state: TxtState = TxtState.IDLE
    answer: Answer | None = None
    answered_at: int = 0
    result: ExchangeResult | None = None
    exchange: Exchange | None = field(default=None, repr=False)
    ticket: object = field(default=None, repr=False)
    table: int | None = None
    indirect: int | None = None
    recv_table: int | None = None

    @property
    def done(self) -> bool:
        return self.state is TxtState.DONE


@dataclass(slots=True)
class _Slot:
    module: IntelligentModule
    present: bool = True
    image: BusImage = field(default_factory=lambda: BusImage((0,) * 8, 0, True))
    ow: list[int] = field(default_factory=lambda: [0] * 8)
    o_bits: int = 0


class Plc:
    """A TSX Series 7 PLC with intelligent modules in its racks."""

    def __init__(
        self,
        model: str = "TSX 87",
        scan_ms: float = 10,
        *,
        clock: SimClock | None = None,
        runner: Any = None,
        speed: float | None = 1.0,
    ) -> None:
        if model not in MODELS:
            raise ConfigError(f"unknown PLC model {model!r} (allowed: {', '.join(MODELS)})")
        if not 1 <= scan_ms <= 1000:
            raise ConfigError(f"scan_ms {scan_ms} out of range (allowed 1..1000 ms)")
        self.model = MODELS[model]
        self.scan_us = round(scan_ms * MS)
        self.clock = clock or SimClock()
        self.runner = runner
        self.speed = speed
        self.running = True
        self.cycles = 0
        self.data = [0] * DATA_WORDS  # internal words W0..W4095
        self._slots: dict[tuple[int, int], _Slot] = {}
        self._txts: dict[int, TextBlock] = {}
        self._scan: Handle | None = self.clock.call_later(self.scan_us, self._end_of_task)

    # --- racks and slots -------------------------------------------------------

    def insert(
        self,
        type_name: str,
        rack: int = 0,
        slot: int = 0,
        *,
        code: int | None = None,
        **options: Any,
    ) -> Any:
        """Put a module in a slot, powered; returns the module object."""
        cls = registry.module_class(type_name)
        self._check_slot(rack, slot)
        ctx = ModuleContext(self.clock, self.model.name, self._enable_pacing)
        module = cls(ctx, rack, slot, declared_code=code, **options)
        self._slots[(rack, slot)] = _Slot(module)
        module.power_on()
        return module

    def _check_slot(self, rack: int, slot: int) -> None:
        if not 0 <= rack < self.model.racks:
            raise ConfigError(
                f"rack {rack} out of range for a {self.model.name}"
                f" (allowed 0..{self.model.racks - 1})"
            )
        if not 0 <= slot < self.model.intelligent_slots:
            raise ConfigError(
                f"slot {slot} cannot take an intelligent module in a {self.model.name}"
                f" (allowed 0..{self.model.intelligent_slots - 1})"
            )
        if (rack, slot) in self._slots:
            raise ConfigError(f"rack {rack} slot {slot} is already taken")
        in_basic = sum(1 for r, _ in self._slots if r == 0)
        if rack == 0 and in_basic >= self.model.basic_rack_max:
            raise ConfigError(
                f"slot {slot}: the basic rack of a {self.model.name} takes at most"
                f" {self.model.basic_rack_max} intelligent modules"
            )

    def module(self, rack: int, slot: int) -> Any:
        try:
            return self._slots[(rack, slot)].module
        except KeyError:
            raise ConfigError(f"no module in rack {rack} slot {slot}") from None

    @property
    def modules(self) -> list[IntelligentModule]:
        return [s.module for _, s in sorted(self._slots.items())]

    def remove(self, rack: int, slot: int) -> None:
        """Pull a module out of its slot under power."""
        entry = self._entry(rack, slot)
        entry.present = False
        entry.module.power_off()

    def reinsert(self, rack: int, slot: int) -> None:
        """Put a pulled module back: it runs its initial self-test."""
        entry = self._entry(rack, slot)
        if not entry.present:
            entry.present = True
            entry.module.power_on()

    def _entry(self, rack: int, slot: int) -> _Slot:
        try:
            return self._slots[(rack, slot)]
        except KeyError:
            raise ConfigError(f"no module in rack {rack} slot {slot}") from None

    # --- time ------------------------------------------------------------------

    def _enable_pacing(self) -> Any:
        """A module wired a real endpoint: time now follows the wall clock."""
        if self.runner is None:
            from fieldtwin.runtime.runner import Runner  # the only bridge to the OS

            self.runner = Runner(self.clock, self.speed)
        return self.runner

    def advance(self, duration_s: float) -> None:
        """Run the simulation for ``duration_s`` simulated seconds."""
        if duration_s < 0:
            raise ConfigError(f"cannot advance by a negative time ({duration_s} s)")
        self._advance_us(seconds(duration_s))

    def _advance_us(self, duration: int) -> None:
        if self.runner is not None:
            self.runner.advance(duration)
        else:
            self.clock.advance(duration)

    def _run_until(self, predicate: Callable[[], bool], limit: int) -> bool:
        if self.runner is not None:
            return bool(self.runner.run_until(predicate, limit))
        end = self.clock.now + limit
        while not predicate():
            deadline = self.clock.next_deadline()
            if deadline is None or deadline > end:
                self.clock.run_until(end)
                break
            self.clock.run_until(deadline)
        return predicate()

    @property
    def now(self) -> int:
        return self.clock.now

    # --- the master task and the bus ------------------------------------------

    def _end_of_task(self, now: int) -> None:
        self.cycles += 1
        registers = self.cycles % self.model.register_every == 0
        for entry in self._slots.values():
            self._refresh(entry, registers, now)
        self._report_answers(now)
        if self.running:
            self._validate_text_blocks(now)
        self._scan = self.clock.call_later(self.scan_us, self._end_of_task)

    def _refresh(self, entry: _Slot, registers: bool, now: int) -> None:
        module = entry.module
        if not entry.present:
            entry.image = BusImage((0,) * 8, 0, True)
            return
        if registers:
            module.bus_write(entry.ow, entry.o_bits, now)
        elif entry.o_bits != module.o_bits:
            module.bus_write(module.ow, entry.o_bits, now)
        if registers:
            entry.image = module.bus_read()
        else:  # TSX 47-20 odd cycle: discrete bits only
            image = module.bus_read()
            entry.image = BusImage(entry.image.iw, image.i_bits, image.fault)

    # --- PLC modes -------------------------------------------------------------

    def stop(self) -> None:
        """PLC to STOP: the master task no longer runs (the bus keeps its image)."""
        self.running = False

    def start(self) -> None:
        self.running = True

    def cold_restart(self) -> None:
        """SY0: modules re-initialised (AEM 2.5-3), images and Text Blocks cleared."""
        self._end_exchanges(ERR_POWER_BREAK)
        for entry in self._slots.values():
            entry.ow = [0] * 8
            entry.o_bits = 0
            if entry.present:
                entry.module.power_off()
                entry.module.power_on()
        self.running = True

    def hot_restart(self) -> None:
        """SY1: the program resumes; modules keep their state."""
        self.running = True

    def power_break(self, duration_s: float) -> None:
        """Cut the PLC supply for ``duration_s`` (simulated)."""
        duration = seconds(duration_s)
        self._end_exchanges(ERR_POWER_BREAK)
        long_break = duration > POWER_RESERVE_US
        present = [e for e in self._slots.values() if e.present]
        if long_break:
            for entry in present:
                entry.module.power_off()
        self._advance_us(duration)
        if long_break:
            for entry in present:
                entry.module.power_on()

    def _end_exchanges(self, code: int) -> None:
        now = self.clock.now
        for txt in self._txts.values():
            if txt.state in (TxtState.STARTED, TxtState.IN_MODULE, TxtState.ANSWERED):
                txt.answer = Answer.fault(code)
                self._finish(txt, now)

    # --- objects -----------------------------------------------------------------

    def read(self, name: str) -> int:
        """An object by its PL7 name: 0/1 for a bit, 0..65535 for a word."""
        w = self._w_address(name)
        if w is not None:
            return self.data[w]
        ref = parse_object(name)
        entry = self._entry(ref.rack, ref.slot)
        if ref.kind is ObjectKind.FAULT:
            return int(entry.image.fault)
        if ref.kind is ObjectKind.I:
            return get_bit(entry.image.i_bits, _index(ref))
        if ref.kind is ObjectKind.O:
            return get_bit(entry.o_bits, _index(ref))
        word = entry.image.iw[_index(ref)] if ref.kind is ObjectKind.IW else entry.ow[_index(ref)]
        return get_bit(word, ref.bit) if ref.bit is not None else word

    def write(self, name: str, value: int) -> None:
        """Write an output object (OWxy,i / OWxy,i,j / Oxy,i) or an internal word Wi."""
        w = self._w_address(name)
        if w is not None:
            self.data[w] = to_unsigned(value)
            return
        ref = parse_object(name)
        entry = self._entry(ref.rack, ref.slot)
        if ref.kind is ObjectKind.OW:
            i = _index(ref)
            if ref.bit is None:
                entry.ow[i] = to_unsigned(value)
            else:
                entry.ow[i] = set_bit(entry.ow[i], ref.bit, _bit_value(name, value))
            return
        if ref.kind is ObjectKind.O:
            outputs = entry.module.discrete_outputs
            if _index(ref) >= outputs:
                raise ConfigError(
                    f"{name!r}: {entry.module.type_name} has "
                    + (
                        f"discrete outputs O,0..O,{outputs - 1:X}"
                        if outputs
                        else "no discrete outputs"
                    )
                )
            entry.o_bits = set_bit(entry.o_bits, _index(ref), _bit_value(name, value))
            return
        raise ConfigError(f"{name!r} is an input: only OWxy,i, OWxy,i,j and Oxy,i can be written")

    def _w_address(self, name: str) -> int | None:
        match = _W_RE.match(name.strip())
        if match is None:
            return None
        address = int(match.group(1))
        if address >= DATA_WORDS:
            raise ConfigError(
                f"{name!r}: internal word out of range (allowed W0..W{DATA_WORDS - 1})"
            )
        return address

    # --- Text Blocks -------------------------------------------------------------

    def text_block(self, index: int) -> TextBlock:
        return self._txts.setdefault(index, TextBlock(index))

    def start_exchange(
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
        tb = self.text_block(txt)
        if tb.state in (TxtState.STARTED, TxtState.IN_MODULE, TxtState.ANSWERED):
            raise ConfigError(
                f"TXT{txt} is busy ({tb.state.value}); reset it or wait for TXT{txt},D"
            )
        for given in (table, recv_table):
            if given is not None and not 0 <= given < DATA_WORDS:
                raise ConfigError(f"table W{given} out of range (allowed W0..W{DATA_WORDS - 1})")
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
        tb.state, tb.answer, tb.result, tb.exchange = TxtState.STARTED, None, None, None
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

    def reset_text_block(self, txt: int) -> None:
        """The Text Block's R input: the exchange in progress ends with TXTi,S = 1."""
        tb = self.text_block(txt)
        if tb.state not in (TxtState.STARTED, TxtState.IN_MODULE, TxtState.ANSWERED):
            return
        tb.ticket = None
        if tb.state is TxtState.IN_MODULE and tb.exchange is not None:
            entry = self._slot_for(tb.m)
            if entry is not None:
                entry.module.cancel_exchange(tb.exchange, self.clock.now)
        tb.answer = Answer.fault(ERR_CANCELLED)
        self._finish(tb, self.clock.now)

    def exchange(
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
        timeout_s: float = 1200.0,
    ) -> ExchangeResult:
        """Start a Text Block exchange and run the simulation until it ends."""
        tb = self.start_exchange(
            m,
            c,
            send,
            send_bytes=send_bytes,
            length=length,
            recv_bytes=recv_bytes,
            txt=txt,
            table=table,
            indirect=indirect,
            recv_table=recv_table,
        )
        if not self._run_until(lambda: tb.done, seconds(timeout_s)) or tb.result is None:
            raise ExchangeTimeout(
                f"TXT{txt} (M={format_hex(m)}, C={format_hex(c, 2)}) not ended after"
                f" {timeout_s} simulated seconds (state {tb.state.value})"
            )
        return tb.result

    def _slot_for(self, m: int) -> _Slot | None:
        rack, slot = (m >> 12) & 0xF, (m >> 8) & 0xF
        return self._slots.get((rack, slot))

    def _validate_text_blocks(self, now: int) -> None:
        for tb in self._txts.values():
            if tb.state is TxtState.STARTED:
                self._validate(tb, now)

    def _validate(self, tb: TextBlock, now: int) -> None:
        table_max = self.model.table_max
        if tb.indirect is not None and self._resolve_table(None, tb.indirect) is None:
            tb.answer, tb.answered_at, tb.state = Answer.fault(ERR_INDIRECT), now, TxtState.ANSWERED
            return
        if len(tb.send) > table_max or tb.capacity > table_max:
            tb.answer = Answer.fault(ERR_TABLE_LENGTH)
            tb.answered_at = now
            tb.state = TxtState.ANSWERED
            return
        channel = tb.m & 0xFF
        entry = self._slot_for(tb.m)
        if entry is None or channel not in (0x00, 0x01, MODULE_SYSTEM):
            tb.answer = Answer.fault(ERR_PARAMETER)
        elif not entry.present or entry.module.state is ModuleState.OFF:
            tb.answer = Answer.fault(ERR_MODULE_FAULT)
        if tb.answer is not None:
            tb.answered_at = now
            tb.state = TxtState.ANSWERED
            return
        assert entry is not None
        tb.state = TxtState.IN_MODULE
        ticket = tb.ticket = object()

        def done(exchange: Exchange, at: int) -> None:
            if tb.ticket is ticket and tb.state is TxtState.IN_MODULE:
                tb.answer, tb.answered_at, tb.state = exchange.answer, at, TxtState.ANSWERED

        tb.exchange = entry.module.submit(Request(tb.c, channel, tb.send, tb.capacity), now, done)

    def _report_answers(self, now: int) -> None:
        for tb in self._txts.values():
            if tb.state is TxtState.ANSWERED and tb.answered_at < now:
                self._finish(tb, now)

    def _finish(self, tb: TextBlock, now: int) -> None:
        answer = tb.answer or Answer.fault(ERR_MODULE_FAULT)
        name = self.model.report_name
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
        tb.state = TxtState.DONE

    # --- status ------------------------------------------------------------------

    def image(self, rack: int, slot: int) -> BusImage:
        return self._entry(rack, slot).image

    def output_words(self, rack: int, slot: int) -> list[int]:
        return list(self._entry(rack, slot).ow)


def _index(ref: ObjectRef) -> int:
    assert ref.index is not None
    return ref.index


def _bit_value(name: str, value: int) -> int:
    if value not in (0, 1):
        raise ConfigError(f"{name!r} is a bit: value {value} not allowed (allowed 0 or 1)")
    return value


__all__ = ["MODELS", "ExchangeResult", "ExchangeTimeout", "Plc", "TextBlock"]
