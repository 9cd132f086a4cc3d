"""The register file of one TES: the words of its memory map (§6), by register kind.

``RegisterFile`` turns a documented word (a :class:`Register`) into behaviour:
``peek`` reads without side effects, ``get`` is a master read (it restores
memorized changes, §4.1.2), ``put`` a master write of a checked writable word.
It reads and writes the TES's RAM (:class:`fieldtwin.tes.state.Ram`) and its
I/O components, all given to ``__init__``.  Every :class:`Kind` has a reader
and every writable kind a writer, in two tables checked complete at import.
``plan`` and ``write_plan`` make a span's reads or writes one call (issue 25 item
2): what ``get_words`` and ``put_words`` do, settled once per span.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping, Sequence
from typing import Any

from fieldtwin.errors import ProtocolError
from fieldtwin.tes import digital, state
from fieldtwin.tes.analog import AnalogInputs
from fieldtwin.tes.digital import BitWord, DigitalInputs, PairWord, Wiring
from fieldtwin.tes.kinds import PAIRS, PARAMETERS, Kind
from fieldtwin.tes.memmap import Register, register_table
from fieldtwin.tes.models import Family, TesModel
from fieldtwin.tes.outputs import DigitalOutputs

ParameterHook = Callable[[Kind, int], None]


class RegisterFile:
    """The memory map of one TES over its RAM and I/O components."""

    def __init__(
        self,
        model: TesModel,
        ram: state.Ram,
        di: DigitalInputs,
        do: DigitalOutputs,
        ai: AnalogInputs,
        on_parameter_write: ParameterHook,
    ) -> None:
        self.model = model
        self.table: Mapping[int, Register] = register_table(model)  # shared per model
        self.ram = ram
        self.di = di
        self.do = do
        self.ai = ai
        self._on_parameter_write = on_parameter_write
        # looked up once: a cache keyed by the model hashes it (and its Enums) per call
        self._pairs = _pair_slots(model)

    # --- reads -------------------------------------------------------------

    def peek(self, reg: Register, now: int) -> int:
        """The word as it stands: no side effect."""
        # by the kind's id: an Enum's hash is computed in Python (ten a 10-word read)
        return _READER_BY_ID[id(reg.kind)](self, reg, now) & 0xFFFF

    def get(self, reg: Register, now: int) -> int:
        """A master read of the word."""
        kind = reg.kind
        if kind is _MEMORIZED:
            self.di.restore_memorized(reg.index)  # AMB-TES-12: shows in this reply
        return _READER_BY_ID[id(kind)](self, reg, now) & 0xFFFF

    def get_words(self, regs: Sequence[Register], now: int) -> tuple[int, ...]:
        """Master reads of consecutive words, in order: ``get`` of each, the 32-bit value
        of a pair computed once for its two words (value32 has no side effect)."""
        out: list[int] = []
        last: tuple[str, int] | None = None
        value = 0
        inputs = self.model.digital_inputs
        pairs = self._pairs  # by address: (kind's name, input, low word) or None
        for reg in regs:
            slot = pairs[reg.address]
            if slot is None:
                out.append(self.get(reg, now))
                continue
            name, i, low = slot
            if i >= inputs:
                out.append(0)  # AMB-TES-13: inputs the model does not have read 0
                continue
            if last != (name, i):
                last, value = (name, i), self.di.value32(name, i, now)
            out.append((value if low else value >> 16) & 0xFFFF)
        return tuple(out)

    def plan(self, regs: Sequence[Register]) -> ReadPlan:
        """Master reads of the consecutive words ``regs`` as one call ``plan(now)``: what
        ``get_words(regs, now)`` returns, with the same side effects in the same order.

        Built once per span (the register file's owner keeps it): what only the model
        decides is settled here (which reader answers each word, the words of inputs or
        channels the model lacks, which read 0), and runs of words that one part answers
        become one step: the status word, the memorized, filtered and direct bit words
        (``DigitalInputs.image``: one call, memorized words restored in address order),
        the halves of 32-bit values (``DigitalInputs.pair_words``), reserved words (a
        constant).  Any other word is its kind's reader, as ``get`` calls it.
        """
        steps: list[_Step] = []
        inputs = self.model.digital_inputs
        pairs = self._pairs
        j, count = 0, len(regs)
        while j < count:
            reg = regs[j]
            kind = reg.kind
            if kind is _ZERO:
                steps.append(((0,), None, 0))
                j += 1
            elif kind in _BIT_KINDS:
                bits: list[BitWord] = []
                while j < count and regs[j].kind in _BIT_KINDS:
                    r = regs[j]
                    first = 16 * r.index
                    bits.append((_STATE_OF_KIND[r.kind], first) if first < inputs else None)
                    j += 1
                spec = tuple(bits)
                steps.append(((), functools.partial(self.di.image, spec), -1))
            elif pairs.get(reg.address) is not None:
                words: list[PairWord] = []
                while j < count and (slot := pairs.get(regs[j].address)) is not None:
                    words.append(slot if slot[1] < inputs else None)
                    j += 1
                steps.append(((), functools.partial(_pair_words, self.di, tuple(words)), -1))
            elif kind is _STATUS:
                steps.append(((), self._status_reader(), 0))
                j += 1
            elif kind is _OUTPUTS:
                steps.append(((), self.do.mask, 16 * reg.index))
                j += 1
            else:
                steps.append(((), functools.partial(_READER_BY_ID[id(kind)], self, reg), 0))
                j += 1
        return _plan_of(_merged(steps))

    def _status_reader(self) -> Callable[[int], int]:
        """``status_word`` as a read plan's step (``now`` unused): what the model has
        settled at once."""
        if self.model.is_analog:
            return lambda now: self.status_word()
        ram, di = self.ram, self.di
        if not self.model.digital_inputs:
            return lambda now: ram.status
        memorized = state.MEMORIZED
        return lambda now: ram.status | memorized if di.changes_pending else ram.status

    def status_word(self) -> int:
        word = self.ram.status
        if self.model.digital_inputs and self.di.changes_pending:
            word |= state.MEMORIZED  # §6.2.1 bit 3, reset by TES once all are read
        if self.model.is_analog:
            channels = self.ai.channels.values()
            word |= state.LOW_ALARM if any(ch.low for ch in channels) else 0
            word |= state.HIGH_ALARM if any(ch.high for ch in channels) else 0
        return word

    def command_word(self, i: int) -> int:
        if self.model.is_analog:  # §6.4.5 blinking choice bits 11-08, states bits 03-00
            return (self.do.blink_select << 8) | self.do.command
        return self.do.command >> (16 * i)

    def pair(self, kind: Kind, index: int, now: int) -> int:
        i, low = divmod(index, 2)
        if i >= self.model.digital_inputs:
            return 0  # AMB-TES-13: inputs the model does not have read 0
        value = self.di.value32(_PAIR_NAMES[kind], i, now)
        return value & 0xFFFF if low else value >> 16

    def wiring_bits(self, wiring: Wiring | None, word: int) -> int:
        """§6.2.7 SC / OC / default words; only inputs wired in security mode report."""
        connection = self.ram.word(0x1AB + word)
        out = 0
        for bit in range(16):
            i = 16 * word + bit  # AMB-TES-23: bit 0 = E1 = input No 0
            w = self.di.wiring(i)
            if (connection >> bit) & 1 and w is not Wiring.OK and wiring in (None, w):
                out |= 1 << bit
        return out

    def safety_default(self) -> bool:
        return self.model.safety and any(self.wiring_bits(None, w) for w in (0, 1))

    def analog_input(self, k: int) -> int:
        ch = self.ai.channels.get(k)
        return 0 if ch is None else ch.value & 0xFFFF

    def channel_state(self, k: int) -> int:
        word = 0x02 if (self.ram.ao_fallback >> k) & 1 else 0  # §6.4.4 bit 1
        ch = self.ai.channels.get(k)
        if ch is not None:
            word |= (0x10 if ch.low else 0) | (0x20 if ch.high else 0)  # bits 4 / 5
        return word

    # --- writes ------------------------------------------------------------

    def put(self, reg: Register, value: int, now: int) -> None:
        """A master write of an already checked writable word."""
        writer = _WRITER_BY_ID.get(id(reg.kind))
        if writer is None or not reg.access.writable:
            raise ProtocolError(
                f"{self.model.name} word {reg.address:03X}h ({reg.name}) is read only"
            )
        writer(self, reg, value, now)

    def put_words(self, regs: Sequence[Register], values: Sequence[int], now: int) -> None:
        """Master writes of consecutive checked writable words, in order: ``put`` of each,
        the two words of a 32-bit pair set at once (what writing them one by one leaves:
        a pair reads back what was written)."""
        inputs = self.model.digital_inputs
        count, j = len(regs), 0
        while j < count:
            reg, kind = regs[j], regs[j].kind
            name = _PAIR_NAME_BY_ID.get(id(kind))  # a pair's kind (no Enum hash)
            if name is not None and j + 1 < count and not reg.index & 1:
                after = regs[j + 1]
                if after.kind is kind and after.index == reg.index + 1:
                    i = reg.index >> 1
                    if i < inputs:  # AMB-TES-13: inputs the model lacks ignore writes
                        value = (values[j] << 16) | values[j + 1]
                        self.di.set_value32(name, i, value, now)
                    j += 2
                    continue
            self.put(reg, values[j], now)
            j += 1

    def write_plan(self, regs: Sequence[Register]) -> WritePlan:
        """Master writes of the consecutive checked writable words ``regs`` as one call
        ``plan(values, now)``: what ``put_words(regs, [v & 0xFFFF for v in values], now)``
        does, in the same order; each run of whole 32-bit values one step
        (``DigitalInputs.set_pair_words``), settled once per span."""
        steps: list[tuple[tuple[PairWord, ...], Register | None]] = []
        inputs = self.model.digital_inputs
        count, j = len(regs), 0
        while j < count:
            if j + 1 < count and _starts_pair(regs, j):
                run: list[PairWord] = []
                while j + 1 < count and _starts_pair(regs, j):
                    reg = regs[j]
                    i = reg.index >> 1  # AMB-TES-13: inputs the model lacks ignore writes
                    run.append((_PAIR_NAME_BY_ID[id(reg.kind)], i, False) if i < inputs else None)
                    j += 2
                steps.append((tuple(run), None))
            else:
                steps.append(((), regs[j]))
                j += 1
        plan = tuple(steps)
        di, put = self.di, self.put

        def write(values: Sequence[int], now: int) -> None:
            k = 0
            for run, reg in plan:
                if reg is None:
                    di.set_pair_words(run, values, k, now)
                    k += 2 * len(run)
                else:
                    put(reg, values[k] & 0xFFFF, now)
                    k += 1

        return write

    def put_command(self, i: int, value: int) -> None:
        do = self.do
        if self.model.is_analog:
            do.blink_select, do.command = (value >> 8) & 0xF, value & 0xF
        else:
            do.command = _splice(do.command, i, value)
        if self.model.family is Family.DIGITAL_INPUTS:
            self.ram.words[0x00D] = do.command & 0xFFFF

    def put_pair(self, kind: Kind, index: int, value: int, now: int) -> None:
        i, low = divmod(index, 2)
        if i >= self.model.digital_inputs:
            return
        old = self.di.value32(kind.value, i, now)
        new = (old & 0xFFFF0000) | value if low else (value << 16) | (old & 0xFFFF)
        self.di.set_value32(kind.value, i, new, now)

    def put_parameter(self, reg: Register, value: int, now: int) -> None:
        self.di.sync()  # inputs followed at read time: their edges so far, old filters
        self.ram.words[reg.address] = value
        self._on_parameter_write(reg.kind, now)


# a read plan's step: (constant words, or a reader of one word shifted right by
# ``shift`` and cut to 16 bits, or of several words when ``shift`` is -1)
_Step = tuple[tuple[int, ...], Callable[[int], Any] | None, int]
ReadPlan = Callable[[int], tuple[int, ...]]


WritePlan = Callable[[Sequence[int], int], None]


def _starts_pair(regs: Sequence[Register], j: int) -> bool:
    """``regs[j]`` and ``regs[j + 1]`` are the two words of one 32-bit value."""
    reg, after = regs[j], regs[j + 1]
    return (
        id(reg.kind) in _PAIR_NAME_BY_ID
        and not reg.index & 1
        and after.kind is reg.kind
        and after.index == reg.index + 1
    )


def _pair_words(di: DigitalInputs, spec: tuple[PairWord, ...], now: int) -> tuple[int, ...]:
    return di.pair_words(spec, now)


def _merged(steps: list[_Step]) -> list[_Step]:
    """Consecutive constant steps as one."""
    out: list[_Step] = []
    for step in steps:
        if step[1] is None and out and out[-1][1] is None:
            out[-1] = (out[-1][0] + step[0], None, 0)
        else:
            out.append(step)
    return out


def _plan_of(steps: list[_Step]) -> ReadPlan:
    if len(steps) == 1:
        const, reader, shift = steps[0]
        if reader is None:
            return lambda now: const
        if shift < 0:
            return reader  # one run of words: its reader is the plan
    plan = tuple(steps)

    def read(now: int) -> tuple[int, ...]:
        out: list[int] = []
        for const, reader, shift in plan:
            if reader is None:
                out += const
            elif shift < 0:
                out += reader(now)
            else:
                out.append((reader(now) >> shift) & 0xFFFF)
        return tuple(out)

    return read


def _splice(mask: int, word: int, value: int) -> int:
    """Replace 16-bit word ``word`` of a 32-bit mask."""
    shift = 16 * word
    return (mask & ~(0xFFFF << shift)) | (value << shift)


# --- the kind tables ---------------------------------------------------------

Reader = Callable[[RegisterFile, Register, int], int]
_PAIR_NAMES = {kind: kind.value for kind in PAIRS}  # an Enum's .value is a slow property
_PAIR_NAME_BY_ID = {id(kind): name for kind, name in _PAIR_NAMES.items()}  # and its hash


@functools.cache
def _pair_slots(model: TesModel) -> dict[int, tuple[str, int, bool] | None]:
    """Each word of ``model``'s map by address: the 32-bit pair it is half of, as
    (kind's name, input, low word), or None (a read's words found by int, not by an
    Enum's hash, which Python computes in Python)."""
    slots: dict[int, tuple[str, int, bool] | None] = {}
    for address, reg in register_table(model).items():
        if reg.kind in PAIRS:
            i, low = divmod(reg.index, 2)
            slots[address] = (_PAIR_NAMES[reg.kind], i, bool(low))
        else:
            slots[address] = None
    return slots


Writer = Callable[[RegisterFile, Register, int, int], None]


def _word(rf: RegisterFile, reg: Register, now: int) -> int:
    return rf.ram.word(reg.address)


def _pair(rf: RegisterFile, reg: Register, now: int) -> int:
    return rf.pair(reg.kind, reg.index, now)


# direct, filtered or memorized bits: the name written out, not the Enum's ``value``
# (a Python-level descriptor, three a 10-word read)
def _memorized(rf: RegisterFile, reg: Register, now: int) -> int:
    return rf.di.bits("memorized", reg.index)


def _filtered(rf: RegisterFile, reg: Register, now: int) -> int:
    return rf.di.bits("filtered", reg.index)


def _direct(rf: RegisterFile, reg: Register, now: int) -> int:
    return rf.di.bits("direct", reg.index)


_READERS: dict[Kind, Reader] = {
    Kind.STATUS: lambda rf, reg, now: rf.status_word(),
    Kind.MEMORIZED: _memorized,
    Kind.FILTERED: _filtered,
    Kind.DIRECT: _direct,
    Kind.OUTPUTS: lambda rf, reg, now: rf.do.mask(now) >> (16 * reg.index),
    Kind.ZERO: lambda rf, reg, now: 0,
    Kind.BLINK_SELECT: lambda rf, reg, now: rf.do.blink_select >> (16 * reg.index),
    Kind.COMMAND: lambda rf, reg, now: rf.command_word(reg.index),
    Kind.DIRECT_IO: lambda rf, reg, now: rf.di.bits("direct", 0) | (rf.do.mask(now) << 8),
    Kind.ANALOG_INPUT: lambda rf, reg, now: rf.analog_input(reg.index),
    Kind.CHANNEL_STATE: lambda rf, reg, now: rf.channel_state(reg.index),
    Kind.ANALOG_OUTPUT: _word,
    Kind.HISTORY: lambda rf, reg, now: rf.ai.history(reg.index // 120, reg.index % 120),
    Kind.DIAG_RS485: lambda rf, reg, now: rf.ram.counters["rs485"].value(reg.index),
    Kind.DIAG_RS232: lambda rf, reg, now: rf.ram.counters["rs232"].value(reg.index),
    Kind.SC: lambda rf, reg, now: rf.wiring_bits(Wiring.SHORT, reg.index),
    Kind.OC: lambda rf, reg, now: rf.wiring_bits(Wiring.OPEN, reg.index),
    Kind.FAULT: lambda rf, reg, now: rf.wiring_bits(None, reg.index),
    **{kind: _pair for kind in PAIRS},
    **{kind: _word for kind in PARAMETERS},
}


def _put_status(rf: RegisterFile, reg: Register, value: int, now: int) -> None:
    rf.ram.status &= value | ~state.MASTER_RESETS[rf.model.family]


def _put_blink_select(rf: RegisterFile, reg: Register, value: int, now: int) -> None:
    rf.do.blink_select = _splice(rf.do.blink_select, reg.index, value)


def _put_diag(rf: RegisterFile, reg: Register, value: int, now: int) -> None:
    rf.ram.counters[reg.kind.value[5:]].set(reg.index, value)


def _put_analog_output(rf: RegisterFile, reg: Register, value: int, now: int) -> None:
    rf.ram.words[reg.address] = value
    rf.ram.ao_fallback &= ~(1 << reg.index)  # a fresh command ends the fallback position


_WRITERS: dict[Kind, Writer] = {
    Kind.STATUS: _put_status,
    Kind.BLINK_SELECT: _put_blink_select,
    Kind.COMMAND: lambda rf, reg, value, now: rf.put_command(reg.index, value),
    Kind.DIAG_RS485: _put_diag,
    Kind.DIAG_RS232: _put_diag,
    Kind.ANALOG_OUTPUT: _put_analog_output,
    **{
        kind: lambda rf, reg, value, now: rf.put_pair(reg.kind, reg.index, value, now)
        for kind in PAIRS
    },
    **{kind: RegisterFile.put_parameter for kind in PARAMETERS},
}

_missing = set(Kind) - set(_READERS)
if _missing:  # pragma: no cover - a programming error caught at import
    raise ImportError(f"TES register kinds without a reader: {sorted(k.value for k in _missing)}")
# the readers by the kind's id (members live as long as the process: ids are fixed)
_READER_BY_ID: dict[int, Reader] = {id(kind): reader for kind, reader in _READERS.items()}
_WRITER_BY_ID: dict[int, Writer] = {id(kind): writer for kind, writer in _WRITERS.items()}
_MEMORIZED = Kind.MEMORIZED
_ZERO, _STATUS, _OUTPUTS = Kind.ZERO, Kind.STATUS, Kind.OUTPUTS
_STATE_OF_KIND = {
    Kind.MEMORIZED: digital.MEMORIZED,
    Kind.FILTERED: digital.FILTERED,
    Kind.DIRECT: digital.DIRECT,
}
_BIT_KINDS = frozenset(_STATE_OF_KIND)
