"""Compile a checked tree into closures: the tree is walked once, at load.

Each instruction becomes a function returning a control code: NEXT, RET or the
index of the sentence a JUMP goes to.  Expressions become functions returning 0/1
(bits), 0..65535 (words), a mask (bit strings) or a list (word tables).
Arithmetic is on 16-bit signed words and wraps (docs/pl7.md).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

from fieldtwin.pl7 import tree as t
from fieldtwin.pl7.errors import ProgramFault
from fieldtwin.pl7.memory import ProgramMemory, Reader, Writer
from fieldtwin.pl7.types import BIT, WORD, Type, bits, words
from fieldtwin.tsx.addressing import ObjectRef

NEXT = -1
RET = -2
MAX_WHILE = 10_000  # iterations of one WHILE before a program fault (docs/pl7.md)

Code = Callable[[], int]
Value = Callable[[], Any]
Put = Callable[[Any], None]


class Runtime(Protocol):
    """What compiled code needs from the executor."""

    edges: list[int]

    def step_reader(self, obj: t.Internal) -> Reader: ...

    def call(self, sr: int) -> None: ...


@dataclass(frozen=True, slots=True)
class Module:
    """A compiled Literal body: its sentences, their lines and labels."""

    name: str
    code: tuple[Code, ...]
    lines: tuple[int, ...]
    labels: tuple[int | None, ...]


def compile_body(
    name: str, items: tuple[t.Sentence | t.Comment, ...], memory: ProgramMemory, rt: Runtime
) -> Module:
    sentences = [s for s in items if isinstance(s, t.Sentence)]
    targets = {s.label: k for k, s in enumerate(sentences) if s.label is not None}
    c = _Compiler(memory, rt, targets)
    return Module(
        name,
        tuple(c.sentence(s) for s in sentences),
        tuple(s.pos.line for s in sentences),
        tuple(s.label for s in sentences),
    )


def compile_condition(node: t.Expr, memory: ProgramMemory, rt: Runtime) -> Reader:
    return _Compiler(memory, rt, {}).value(node)


def type_of(node: t.Expr) -> Type:
    if isinstance(node, t.Internal):
        return BIT if node.is_bit else WORD
    if isinstance(node, t.ModuleObj):
        return BIT if node.ref.is_bit else WORD
    if isinstance(node, t.TxtField):
        return BIT if node.is_bit else WORD
    if isinstance(node, t.Table):
        start = node.start
        is_bits = isinstance(start, t.ModuleObj) or start.kind == "B"
        return bits(node.length) if is_bits else words(node.length)
    if isinstance(node, t.Bta):
        return words(3)
    if isinstance(node, t.Binary):
        return BIT if node.op.on_bits else WORD
    if isinstance(node, t.InternalBit | t.Not | t.Edge | t.Compare):
        return BIT
    return WORD


def _signed(v: int) -> int:
    return v - 0x10000 if v & 0x8000 else v


class _Compiler:
    def __init__(self, memory: ProgramMemory, rt: Runtime, labels: dict[int, int]) -> None:
        self.m = memory
        self.rt = rt
        self.labels = labels

    # --- statements -------------------------------------------------------------------

    def sentence(self, sentence: t.Sentence) -> Code:
        return _sequence([self.statement(s) for s in sentence.body])

    def statement(self, node: t.Statement) -> Code:
        if isinstance(node, t.If):
            return self.if_(node)
        if isinstance(node, t.While):
            return self.while_(node)
        return self.action(node)

    def if_(self, node: t.If) -> Code:
        cond = self.value(node.condition)
        then = _sequence([self.action(a) for a in node.then])
        if node.otherwise is None:
            return lambda: then() if cond() else NEXT
        otherwise = _sequence([self.action(a) for a in node.otherwise])
        return lambda: then() if cond() else otherwise()

    def while_(self, node: t.While) -> Code:
        cond = self.value(node.condition)
        body = _sequence([self.action(a) for a in node.body])

        def run() -> int:
            count = 0
            while cond():
                count += 1
                if count > MAX_WHILE:
                    raise ProgramFault(f"WHILE did not end within {MAX_WHILE} iterations")
                code = body()
                if code != NEXT:
                    return code
            return NEXT

        return run

    def action(self, node: t.Action) -> Code:
        if isinstance(node, t.Assign):
            return self.assign(node)
        if isinstance(node, t.SetBit):
            write = self.writer(node.target, BIT)
            value = 1 if node.value else 0
            return lambda: (write(value), NEXT)[1]
        if isinstance(node, t.Step):
            read, put = self.value(node.target), self.writer(node.target, WORD)
            delta = 1 if node.up else 0xFFFF
            return lambda: (put((read() + delta) & 0xFFFF), NEXT)[1]
        if isinstance(node, t.TxtOp):
            return self.txt_op(node)
        if isinstance(node, t.Jump):
            target = self.labels[node.label]
            return lambda: target
        if isinstance(node, t.Call):
            call, sr = self.rt.call, node.sr
            return lambda: (call(sr), NEXT)[1]
        return lambda: RET

    def txt_op(self, node: t.TxtOp) -> Code:
        index, m, command = node.index, self.m, node.op
        if command == "RESET":

            def reset() -> int:
                m.txt_reset(index)
                return NEXT

            return reset

        def start() -> int:
            m.txt_start(index, command)
            return NEXT

        return start

    def assign(self, node: t.Assign) -> Code:
        source_type = type_of(node.source)
        value = self.value(node.source)
        puts = [self.writer(target, source_type) for target in node.targets]
        if len(puts) == 1:
            put = puts[0]
            return lambda: (put(value()), NEXT)[1]

        def run() -> int:
            v = value()
            for p in puts:
                p(v)
            return NEXT

        return run

    # --- writers ----------------------------------------------------------------------

    def writer(self, target: t.Expr, source: Type) -> Put:
        """A function that stores a value of type ``source`` into ``target``."""
        if isinstance(target, t.Table):
            return self.table_writer(target, source)
        if isinstance(target, t.Indexed):
            write_at = self.m.indexed_writer(target.base)
            offset = self.m.word_reader(target.index)
            return lambda v: write_at(offset(), v)
        assert isinstance(target, t.Internal | t.InternalBit | t.ModuleObj | t.TxtField)
        if type_of(target) == BIT:
            return self.m.bit_writer(target)
        assert not isinstance(target, t.InternalBit)
        return self.m.word_writer(target)  # a bit string goes in as its mask, bit 0 first

    def table_writer(self, target: t.Table, source: Type) -> Put:
        elements = self.elements(target)
        if type_of(target).kind == "bits":
            bit_writers: list[Writer] = [self.m.bit_writer(e) for e in elements]

            def put_bits(v: int) -> None:
                for k, w in enumerate(bit_writers):
                    w((v >> k) & 1)

            return put_bits
        word_writers: list[Writer] = [self.m.word_writer(e) for e in elements]
        if source == WORD:

            def fill(v: int) -> None:
                for w in word_writers:
                    w(v)

            return fill

        def copy(values: list[int]) -> None:
            for w, v in zip(word_writers, values, strict=True):
                w(v)

        return copy

    def elements(self, table: t.Table) -> list[t.Internal | t.ModuleObj]:
        start = table.start
        if isinstance(start, t.Internal):
            return [t.Internal(start.kind, start.index + k) for k in range(table.length)]
        ref = start.ref
        base = ref.index or 0
        return [
            t.ModuleObj(ObjectRef(ref.kind, ref.rack, ref.slot, base + k))
            for k in range(table.length)
        ]

    # --- expressions --------------------------------------------------------------------

    def value(self, node: t.Expr) -> Value:
        if isinstance(node, t.Const):
            constant = node.value
            return lambda: constant
        if isinstance(node, t.Internal):
            if node.kind in ("X", "XM"):
                return self.rt.step_reader(node)
            return self.m.bit_reader(node) if node.is_bit else self.m.word_reader(node)
        if isinstance(node, t.InternalBit):
            return self.m.bit_reader(node)
        if isinstance(node, t.ModuleObj | t.TxtField):
            return self.m.bit_reader(node) if type_of(node) == BIT else self.m.word_reader(node)
        if isinstance(node, t.Table):
            return self.table_value(node)
        if isinstance(node, t.Indexed):
            read_at, offset = self.m.indexed_reader(node.base), self.m.word_reader(node.index)
            return lambda: read_at(offset())
        if isinstance(node, t.Not):
            operand = self.value(node.operand)
            return lambda: 1 - operand()
        if isinstance(node, t.Edge):
            return self.edge(node)
        if isinstance(node, t.Compare):
            return self.compare(node)
        if isinstance(node, t.Shift):
            operand, n = self.value(node.operand), node.count
            if node.left:
                return lambda: (operand() << n) & 0xFFFF
            return lambda: operand() >> n
        if isinstance(node, t.Bta):
            return _bta(self.value(node.operand))
        assert isinstance(node, t.Binary)
        return self.binary(node)

    def table_value(self, node: t.Table) -> Value:
        elements = self.elements(node)
        if type_of(node).kind == "bits":
            readers = [self.m.bit_reader(e) for e in elements]

            def mask() -> int:
                v = 0
                for k, r in enumerate(readers):
                    v |= r() << k
                return v

            return mask
        word_readers = [self.m.word_reader(e) for e in elements]
        return lambda: [r() for r in word_readers]

    def edge(self, node: t.Edge) -> Value:
        # RE/FE: each occurrence compares its bit with the value it had when this
        # occurrence was last evaluated (0 after a cold restart): docs/pl7.md
        read, edges = self.value(node.operand), self.rt.edges
        k = len(edges)
        edges.append(0)
        if node.rising:

            def rising() -> int:
                v = read()
                before = edges[k]
                edges[k] = v
                return 1 if v and not before else 0

            return rising

        def falling() -> int:
            v = read()
            before = edges[k]
            edges[k] = v
            return 1 if before and not v else 0

        return falling

    def compare(self, node: t.Compare) -> Value:
        a, b = self.value(node.left), self.value(node.right)
        op = node.op
        if op == "=":
            return lambda: 1 if a() == b() else 0
        if op == "<>":
            return lambda: 1 if a() != b() else 0
        s = _signed
        if op == "<":
            return lambda: 1 if s(a()) < s(b()) else 0
        if op == ">":
            return lambda: 1 if s(a()) > s(b()) else 0
        if op == "<=":
            return lambda: 1 if s(a()) <= s(b()) else 0
        return lambda: 1 if s(a()) >= s(b()) else 0

    def binary(self, node: t.Binary) -> Value:
        a, b = self.value(node.left), self.value(node.right)
        op = node.op
        # no short cut: both operands are evaluated, so that every RE/FE keeps its memory
        simple: dict[t.Op, Value] = {
            t.Op.AND: lambda: a() & b(),
            t.Op.OR: lambda: a() | b(),
            t.Op.WAND: lambda: a() & b(),
            t.Op.WOR: lambda: a() | b(),
            t.Op.WXOR: lambda: a() ^ b(),
            t.Op.ADD: lambda: (a() + b()) & 0xFFFF,
            t.Op.SUB: lambda: (a() - b()) & 0xFFFF,
            t.Op.MUL: lambda: (_signed(a()) * _signed(b())) & 0xFFFF,
        }
        if op in simple:
            return simple[op]
        return _division(a, b, op is t.Op.REM)


def _division(a: Value, b: Value, remainder: bool) -> Value:
    def divide() -> int:
        x, y = _signed(a()), _signed(b())
        if y == 0:
            raise ProgramFault("division by zero" if not remainder else "REM by zero")
        q = abs(x) // abs(y) * (1 if (x < 0) == (y < 0) else -1)  # towards zero
        return ((x - q * y) if remainder else q) & 0xFFFF

    return divide


def _bta(operand: Value) -> Value:
    # BTA: a signed word in 6 ASCII characters, the sign then 5 digits, the first
    # character in the low byte of the first word (DEM 5.3-4 SR0 uses W162 for the
    # last two digits and the high byte of W161 for the hundreds): docs/manual-notes.md
    def convert() -> list[int]:
        v = _signed(operand())
        text = ("-" if v < 0 else "+") + f"{abs(v):05d}"
        raw = text.encode("ascii")
        return [raw[k] | (raw[k + 1] << 8) for k in range(0, 6, 2)]

    return convert


def _sequence(codes: list[Code]) -> Code:
    if len(codes) == 1:
        return codes[0]
    if not codes:
        return lambda: NEXT
    frozen = tuple(codes)

    def run() -> int:
        for code in frozen:
            r = code()
            if r != NEXT:
                return r
        return NEXT

    return run
