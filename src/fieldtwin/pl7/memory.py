"""What a program runs against: the ``ProgramMemory`` protocol, and an in-memory one.

The executor asks the memory once, when it compiles the program, for a reader or a
writer of each object; every master task then only calls them.  A PLC implements
the protocol over its own images (internal words, bus images, Text Blocks).

Values are 0/1 for bits and 0..65535 for words.  A reader or writer that cannot
serve at run time (an index out of its table, a Text Block misuse) raises
ProgramFault; the executor records it and goes on.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol

from fieldtwin.objects import ObjectKind, ObjectRef, parse_object
from fieldtwin.pl7 import tree as t
from fieldtwin.pl7.checker import DEFAULT_LIMITS, Limits
from fieldtwin.pl7.errors import ProgramFault

Reader = Callable[[], int]
Writer = Callable[[int], None]
IndexedReader = Callable[[int], int]
IndexedWriter = Callable[[int, int], None]
BitObject = t.Internal | t.InternalBit | t.ModuleObj | t.TxtField
WordObject = t.Internal | t.ModuleObj | t.TxtField
# (list, index, bit): the object is list[index] (bit None: a 0/1 bit or a word) or bit
# ``bit`` of the word list[index]; the compiled program reads and writes it in place.
Cell = tuple[list[int], int, int | None]

TXT_COMMANDS = ("EXCHG", "INPUT", "OUTPUT")  # SCM 2.2: EXCHG (S, I, O), OUTPUT (S, O)
ERR_CANCELLED = 1  # TXTi,S = 1: "exchange in progress was cancelled by reset" (SCM 4.5)


class ProgramMemory(Protocol):
    """The objects of a PLC as a program sees them."""

    def cell(self, obj: BitObject | WordObject) -> Cell | None:
        """Where the object lives, if it is a plain list element (the fast way); else None
        and the compiled program goes through the readers and writers."""
        ...

    def bit_reader(self, obj: BitObject) -> Reader: ...

    def bit_writer(self, obj: BitObject) -> Writer: ...

    def word_reader(self, obj: WordObject) -> Reader: ...

    def word_writer(self, obj: WordObject) -> Writer: ...

    def indexed_reader(self, base: t.Internal) -> IndexedReader:
        """``W0(W124)``: a reader of W[base + offset]; ProgramFault past the table."""
        ...

    def indexed_writer(self, base: t.Internal) -> IndexedWriter: ...

    def txt_start(self, index: int, command: str) -> None:
        """EXCHG / INPUT / OUTPUT TXTi with its M, C, L inputs; validated by the PLC."""
        ...

    def txt_reset(self, index: int) -> None:
        """RESET TXTi: the exchange in progress ends (TXTi,E = 1, TXTi,S = 1)."""
        ...

    def clear_internal(self) -> None:
        """A cold restart: internal bits and words to 0 (constant words are kept)."""
        ...


@dataclass(slots=True)
class ModuleImage:
    """The objects of one module slot in the in-memory memory."""

    iw: list[int] = field(default_factory=lambda: [0] * 8)
    ow: list[int] = field(default_factory=lambda: [0] * 8)
    i: list[int] = field(default_factory=lambda: [0] * 16)
    o: list[int] = field(default_factory=lambda: [0] * 16)
    fault: list[int] = field(default_factory=lambda: [0])


@dataclass(frozen=True, slots=True)
class Started:
    """One Text Block exchange a program started (for tests and scripted modules)."""

    index: int
    command: str
    m: int
    c: int
    length: int


TXT_FIELDS = t.TXT_WORD_FIELDS + t.TXT_BIT_FIELDS


class InMemory:
    """Lists for every table; modules and Text Blocks made on first use.

    ``finish(i, v=..)`` ends an exchange as a module would (TXTi,D = 1).
    """

    def __init__(self, limits: Limits = DEFAULT_LIMITS) -> None:
        self.limits = limits
        self.b = [0] * limits.bits
        self.w = [0] * limits.words
        self.cw = [0] * limits.constant_words
        self.sy = [0] * limits.system_bits
        self.sw = [0] * limits.system_words
        self.modules: dict[tuple[int, int], ModuleImage] = {}
        self.txt: dict[int, dict[str, int]] = {}
        self.busy: set[int] = set()
        self.started: list[Started] = []

    # --- tests and scripted modules -----------------------------------------------------

    def module(self, rack: int, slot: int) -> ModuleImage:
        return self.modules.setdefault((rack, slot), ModuleImage())

    def text_block(self, index: int) -> dict[str, int]:
        # D = 1 before the first exchange: the SCM 4.6 SR7 starts on "TXT0,D.B129"
        return self.txt.setdefault(index, dict.fromkeys(TXT_FIELDS, 0) | {"D": 1})

    def finish(self, index: int, v: int = 0, s: int = 0, error: bool = False) -> None:
        fields = self.text_block(index)
        fields.update(V=v, R=v, S=s, E=int(error), D=1)
        self.busy.discard(index)

    def read(self, name: str) -> int:
        """A module object by name (``IW5,2,D``, ``O16,C``): for tests."""
        ref = parse_object(name)
        return self._module_reader(ref)()

    def write(self, name: str, value: int) -> None:
        ref = parse_object(name)
        if ref.is_bit:
            self._module_bit_writer(ref)(value)
        else:
            self._module_word_list(ref)[ref.index or 0] = value & 0xFFFF

    # --- ProgramMemory ----------------------------------------------------------------

    def _table(self, kind: str) -> list[int]:
        return {"B": self.b, "W": self.w, "CW": self.cw, "SY": self.sy, "SW": self.sw}[kind]

    def cell(self, obj: BitObject | WordObject) -> Cell | None:
        if isinstance(obj, t.Internal):
            return self._table(obj.kind), obj.index, None
        if isinstance(obj, t.InternalBit):
            return self._table(obj.word.kind), obj.word.index, obj.bit
        if isinstance(obj, t.TxtField):
            return None
        ref = obj.ref
        image = self.module(ref.rack, ref.slot)
        if ref.kind is ObjectKind.FAULT:
            return image.fault, 0, None
        if ref.kind in (ObjectKind.I, ObjectKind.O):
            return (image.i if ref.kind is ObjectKind.I else image.o), ref.index or 0, None
        return self._module_word_list(ref), ref.index or 0, ref.bit

    def bit_reader(self, obj: BitObject) -> Reader:
        if isinstance(obj, t.Internal):
            table, i = self._table(obj.kind), obj.index
            return lambda: table[i]
        if isinstance(obj, t.InternalBit):
            table, i, bit = self._table(obj.word.kind), obj.word.index, obj.bit
            return lambda: (table[i] >> bit) & 1
        if isinstance(obj, t.TxtField):
            fields, name = self.text_block(obj.index), obj.name
            return lambda: fields[name]
        return self._module_reader(obj.ref)

    def bit_writer(self, obj: BitObject) -> Writer:
        if isinstance(obj, t.Internal):
            table, i = self._table(obj.kind), obj.index

            def write(value: int) -> None:
                table[i] = value

            return write
        if isinstance(obj, t.InternalBit):
            table, i, mask = self._table(obj.word.kind), obj.word.index, 1 << obj.bit

            def write_bit(value: int) -> None:
                table[i] = (table[i] | mask) if value else (table[i] & ~mask)

            return write_bit
        if isinstance(obj, t.TxtField):
            raise ProgramFault(f"TXT{obj.index},{obj.name} is an output of the Text Block")
        return self._module_bit_writer(obj.ref)

    def word_reader(self, obj: WordObject) -> Reader:
        if isinstance(obj, t.Internal):
            table, i = self._table(obj.kind), obj.index
            return lambda: table[i]
        if isinstance(obj, t.TxtField):
            fields, name = self.text_block(obj.index), obj.name
            return lambda: fields[name]
        return self._module_reader(obj.ref)

    def word_writer(self, obj: WordObject) -> Writer:
        if isinstance(obj, t.Internal):
            table, i = self._table(obj.kind), obj.index
        elif isinstance(obj, t.TxtField):
            fields, name = self.text_block(obj.index), obj.name

            def write_field(value: int) -> None:
                fields[name] = value

            return write_field
        else:
            table, i = self._module_word_list(obj.ref), obj.ref.index or 0

        def write(value: int) -> None:
            table[i] = value

        return write

    def indexed_reader(self, base: t.Internal) -> IndexedReader:
        table, start, size = self._table(base.kind), base.index, len(self._table(base.kind))

        def read(offset: int) -> int:
            at = start + offset
            if at >= size:
                raise ProgramFault(f"{base.kind}{start}({offset}): {base.kind}{at} past the table")
            return table[at]

        return read

    def indexed_writer(self, base: t.Internal) -> IndexedWriter:
        table, start, size = self._table(base.kind), base.index, len(self._table(base.kind))

        def write(offset: int, value: int) -> None:
            at = start + offset
            if at >= size:
                raise ProgramFault(f"{base.kind}{start}({offset}): {base.kind}{at} past the table")
            table[at] = value

        return write

    def txt_start(self, index: int, command: str) -> None:
        fields = self.text_block(index)
        if index in self.busy:
            raise ProgramFault(f"{command} TXT{index}: its exchange is still in progress")
        self.busy.add(index)
        fields.update(D=0, E=0)
        self.started.append(Started(index, command, fields["M"], fields["C"], fields["L"]))

    def txt_reset(self, index: int) -> None:
        if index in self.busy:
            self.finish(index, s=ERR_CANCELLED, error=True)

    def clear_internal(self) -> None:
        self.b[:] = [0] * len(self.b)
        self.w[:] = [0] * len(self.w)

    # --- modules ------------------------------------------------------------------------

    def _module_word_list(self, ref: ObjectRef) -> list[int]:
        image = self.module(ref.rack, ref.slot)
        return image.iw if ref.kind is ObjectKind.IW else image.ow

    def _module_reader(self, ref: ObjectRef) -> Reader:
        image = self.module(ref.rack, ref.slot)
        if ref.kind is ObjectKind.FAULT:
            fault = image.fault
            return lambda: fault[0]
        if ref.kind in (ObjectKind.I, ObjectKind.O):
            table, i = (image.i if ref.kind is ObjectKind.I else image.o), ref.index or 0
            return lambda: table[i]
        words, i = self._module_word_list(ref), ref.index or 0
        if ref.bit is None:
            return lambda: words[i]
        bit = ref.bit
        return lambda: (words[i] >> bit) & 1

    def _module_bit_writer(self, ref: ObjectRef) -> Writer:
        image = self.module(ref.rack, ref.slot)
        if ref.kind is ObjectKind.FAULT:
            fault = image.fault

            def write_fault(value: int) -> None:
                fault[0] = value

            return write_fault
        if ref.kind in (ObjectKind.I, ObjectKind.O):
            table, i = (image.i if ref.kind is ObjectKind.I else image.o), ref.index or 0

            def write(value: int) -> None:
                table[i] = value

            return write
        words, i, mask = self._module_word_list(ref), ref.index or 0, 1 << (ref.bit or 0)

        def write_bit(value: int) -> None:
            words[i] = (words[i] | mask) if value else (words[i] & ~mask)

        return write_bit
