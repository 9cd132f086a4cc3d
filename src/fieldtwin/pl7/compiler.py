"""Compile a checked tree into Python functions, once, at load.

Each sentence becomes one Python function (its source generated here and compiled
with ``compile``), with the objects bound in: a cell the memory lends
(``ProgramMemory.cell``: a list and an index) is read and written in place, any
other object through the reader or writer the memory gives.  A sentence function
returns a control code: NEXT, RET or the index of the sentence a JUMP goes to.
The tree is never walked again while the program runs.

The task watchdog's budget (docs/pl7.md, "The task watchdog"): each chunk has a
cost in operations (one per object read or written, operator, comparison and
instruction of its sentences, both branches of an IF counted), spent by the
executor before it runs the chunk; a WHILE spends its body's cost at each pass
after the first.  Past the budget the code raises WatchdogOverrun, which no
sentence catches: the task is cut there.

Values: 0/1 for bits, 0..65535 for words (arithmetic on signed 16-bit words,
wrapping), a mask for bit strings (bit 0 first), a list for word tables.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

from fieldtwin.errors import ConfigError
from fieldtwin.objects import ObjectRef
from fieldtwin.pl7 import tree as t
from fieldtwin.pl7.errors import ObjectRefused, Pl7Error, ProgramFault, WatchdogOverrun
from fieldtwin.pl7.memory import ProgramMemory, Reader
from fieldtwin.pl7.printer import format_object, format_sentence
from fieldtwin.pl7.types import BIT, WORD, Type, bits, words

NEXT = -1
RET = -2
MAX_WHILE = 10_000  # iterations of one WHILE before a program fault (docs/pl7.md)

Code = Callable[[], int]


class Runtime(Protocol):
    """What compiled code needs from the executor."""

    edges: list[int]

    @property
    def budget_cell(self) -> list[int]:
        """[operations left in the master task running] (the watchdog's budget)."""
        ...

    def step_cells(self, obj: t.Internal) -> tuple[list[int], tuple[int, ...]]: ...

    def call(self, sr: int) -> None: ...

    def fault(self, module: str, line: int, err: ProgramFault) -> None: ...

    def watch(self, module: str) -> set[int]:
        """The labels of ``module`` with a breakpoint (the set is kept and updated)."""
        ...

    def hit(self, module: str, label: int) -> None: ...


@dataclass(frozen=True, slots=True)
class Module:
    """A compiled Literal body: chunks of sentences, each starting where a JUMP lands.

    ``code[k]`` runs the sentences of chunk k; a fault in one of them abandons that
    sentence only (it is recorded with its line) and the chunk goes on.
    """

    name: str
    code: tuple[Code, ...]
    lines: tuple[int, ...]  # the line of each chunk's first sentence
    labels: tuple[int, ...]  # every label of the body
    costs: tuple[int, ...] = ()  # each chunk's operations (the watchdog's budget)


def compile_body(
    name: str, items: tuple[t.Sentence | t.Comment, ...], memory: ProgramMemory, rt: Runtime
) -> Module:
    sentences = [s for s in items if isinstance(s, t.Sentence)]
    landing = {a.label for s in sentences for a in _jumps(s.body)}
    chunks: list[list[t.Sentence]] = []
    for sentence in sentences:
        if not chunks or sentence.label in landing:
            chunks.append([])
        chunks[-1].append(sentence)
    targets = {c[0].label: k for k, c in enumerate(chunks) if c[0].label is not None}
    gen = _Generator(memory, rt, targets, name)
    hooks = (
        gen.bind(lambda line, err: rt.fault(name, line, err)),
        gen.bind(rt.watch(name)),
        gen.bind(lambda label: rt.hit(name, label)),
    )
    code: list[Code] = []
    costs: list[int] = []
    for c in chunks:
        gen.ops = 0
        code.append(gen.chunk(c, hooks))
        costs.append(max(1, gen.ops))
    return Module(
        name,
        tuple(code),
        tuple(c[0].pos.line for c in chunks),
        tuple(s.label for s in sentences if s.label is not None),
        tuple(costs),
    )


def _jumps(body: tuple[t.Statement, ...]) -> list[t.Jump]:
    out: list[t.Jump] = []
    for statement in body:
        if isinstance(statement, t.If):
            actions = statement.then + (statement.otherwise or ())
        elif isinstance(statement, t.While):
            actions = statement.body
        else:
            actions = (statement,)
        out.extend(a for a in actions if isinstance(a, t.Jump))
    return out


def compile_condition(node: t.Expr, memory: ProgramMemory, rt: Runtime) -> Reader:
    gen = _Generator(memory, rt, {}, "condition")
    code = gen.function(["return " + gen.expr(node)], "condition")
    return code


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


def _div(a: int, b: int) -> int:
    x, y = _signed(a), _signed(b)
    if y == 0:
        raise ProgramFault("division by zero")
    q = abs(x) // abs(y)
    return (q if (x < 0) == (y < 0) else -q) & 0xFFFF  # towards zero


def _rem(a: int, b: int) -> int:
    x, y = _signed(a), _signed(b)
    if y == 0:
        raise ProgramFault("REM by zero")
    q = abs(x) // abs(y)
    q = q if (x < 0) == (y < 0) else -q
    return (x - q * y) & 0xFFFF  # the sign of the dividend


def _bta(value: int) -> list[int]:
    # BTA: a signed word in 6 ASCII characters, the sign then 5 digits, the first
    # character in the low byte of the first word (DEM 5.3-4 SR0 uses W162 for the
    # last two digits and the high byte of W161 for the hundreds): manual-notes.md
    v = _signed(value)
    raw = (("-" if v < 0 else "+") + f"{abs(v):05d}").encode("ascii")
    return [raw[k] | (raw[k + 1] << 8) for k in range(0, 6, 2)]


def _while_fault() -> ProgramFault:
    return ProgramFault(f"WHILE did not end within {MAX_WHILE} iterations")


_BASE: dict[str, Any] = {
    "_div": _div,
    "_rem": _rem,
    "_bta": _bta,
    "_while_fault": _while_fault,
    "MAX_WHILE": MAX_WHILE,
    "_PF": ProgramFault,
    "_WD": WatchdogOverrun,
}
_WORD_OPS = {
    t.Op.WAND: "({a} & {b})",
    t.Op.WOR: "({a} | {b})",
    t.Op.WXOR: "({a} ^ {b})",
    t.Op.ADD: "(({a} + {b}) & 65535)",
    t.Op.SUB: "(({a} - {b}) & 65535)",
    # the product of the signed words, modulo 2**16, is that of the unsigned ones
    t.Op.MUL: "(({a} * {b}) & 65535)",
    t.Op.DIV: "_div({a}, {b})",
    t.Op.REM: "_rem({a}, {b})",
    t.Op.AND: "({a} & {b})",  # no short cut: every RE/FE keeps its memory
    t.Op.OR: "({a} | {b})",
}
# signed order is the unsigned order of the words with their sign bit flipped
_COMPARE = {
    "=": "(1 if {a} == {b} else 0)",
    "<>": "(1 if {a} != {b} else 0)",
    "<": "(1 if ({a} ^ 32768) < ({b} ^ 32768) else 0)",
    ">": "(1 if ({a} ^ 32768) > ({b} ^ 32768) else 0)",
    "<=": "(1 if ({a} ^ 32768) <= ({b} ^ 32768) else 0)",
    ">=": "(1 if ({a} ^ 32768) >= ({b} ^ 32768) else 0)",
}


class _Generator:
    def __init__(
        self, memory: ProgramMemory, rt: Runtime, labels: dict[int, int], module: str
    ) -> None:
        self.m = memory
        self.rt = rt
        self.labels = labels
        self.module = module
        self.env: dict[str, Any] = dict(_BASE)
        self.names: dict[int, str] = {}
        self.temps = 0
        self.ops = 0  # operations of the code generated so far (the watchdog's cost)
        self.line = 0  # the line of the sentence being compiled
        self.object: t.Expr | None = None  # the object being bound (named if refused)

    def bind(self, value: object) -> str:
        name = self.names.get(id(value))
        if name is None:
            name = f"_o{len(self.env)}"
            self.env[name] = value
            self.names[id(value)] = name
        return name

    def temp(self) -> str:
        self.temps += 1
        return f"_v{self.temps}"

    def function(self, body: list[str], title: str) -> Code:
        source = "def _f():\n" + "".join(f"    {line}\n" for line in body)
        namespace: dict[str, Any] = {}
        exec(compile(source, f"<pl7 {title}>", "exec"), self.env, namespace)
        code: Code = namespace["_f"]
        return code

    # --- statements -------------------------------------------------------------------

    def chunk(self, sentences: list[t.Sentence], hooks: tuple[str, str, str]) -> Code:
        fault, watch, hit = hooks
        lines: list[str] = []
        for sentence in sentences:
            self.line = sentence.pos.line
            if sentence.label is not None:
                lines += [f"if {watch} and {sentence.label} in {watch}:"]
                lines += [f"    {hit}({sentence.label})"]
            body: list[str] = []
            try:
                for statement in sentence.body:
                    body.extend(self.statement(statement))
            except (Pl7Error, ObjectRefused):
                raise
            except ConfigError as exc:  # the PLC refused an object: name it, with its line
                token = format_object(self.object) if self.object is not None else ""
                raise ObjectRefused(sentence.pos.line, token, str(exc)) from None
            lines += ["try:", *_indent(body), "except _PF as _e:"]
            lines += [f"    {fault}({sentence.pos.line}, _e)"]
        lines.append(f"return {NEXT}")
        return self.function(lines, format_sentence(sentences[0])[:60])

    def statement(self, node: t.Statement) -> list[str]:
        self.ops += 1
        if isinstance(node, t.If):
            out = [f"if {self.expr(node.condition)}:"]
            out += _indent(self.actions(node.then))
            if node.otherwise is not None:
                out += ["else:", *_indent(self.actions(node.otherwise))]
            return out
        if isinstance(node, t.While):
            count = self.temp()
            before = self.ops
            condition = self.expr(node.condition)
            actions = self.actions(node.body)
            # each pass after the first spends the body's cost (the first is the chunk's)
            budget, cost = self.bind(self.rt.budget_cell), self.ops - before + 1
            body = [f"{count} += 1", f"if {count} > MAX_WHILE:", "    raise _while_fault()"]
            body += [f"if {count} > 1:", f"    {budget}[0] -= {cost}"]
            body += [f"    if {budget}[0] < 0:", f"        raise _WD({self.module!r}, {self.line})"]
            body += actions
            return [f"{count} = 0", f"while {condition}:", *_indent(body)]
        return self.action(node)

    def actions(self, actions: tuple[t.Action, ...]) -> list[str]:
        out: list[str] = []
        for action in actions:
            out.extend(self.action(action))
        return out

    def action(self, node: t.Action) -> list[str]:
        self.ops += 1
        if isinstance(node, t.Assign):
            value = self.temp()
            out = [f"{value} = {self.expr(node.source)}"]
            source_type = type_of(node.source)
            for target in node.targets:
                out.extend(self.store(target, value, source_type))
            return out
        if isinstance(node, t.SetBit):
            return self.store(node.target, "1" if node.value else "0", BIT)
        if isinstance(node, t.Step):
            delta = "1" if node.up else "65535"
            value = self.temp()
            read = self.expr(node.target)
            return [f"{value} = ({read} + {delta}) & 65535", *self.store(node.target, value, WORD)]
        if isinstance(node, t.TxtOp):
            if node.op == "RESET":
                return [f"{self.bind(self.m.txt_reset)}({node.index})"]
            return [f"{self.bind(self.m.txt_start)}({node.index}, {node.op!r})"]
        if isinstance(node, t.Jump):
            return [f"return {self.labels[node.label]}"]
        if isinstance(node, t.Call):
            return [f"{self.bind(self.rt.call)}({node.sr})"]
        return [f"return {RET}"]

    def store(self, target: t.Expr, value: str, source: Type) -> list[str]:
        """Lines that store ``value`` (of type ``source``) into ``target``."""
        self.ops += 1
        self.object = target
        if isinstance(target, t.Table):
            return self.store_table(target, value, source)
        if isinstance(target, t.Indexed):
            write_at = self.bind(self.m.indexed_writer(target.base))
            return [f"{write_at}({self.expr(target.index)}, {value})"]
        assert isinstance(target, t.Internal | t.InternalBit | t.ModuleObj | t.TxtField)
        cell = self.m.cell(target)
        if cell is not None:
            table, index, bit = cell
            ref = f"{self.bind(table)}[{index}]"
            if bit is None:
                return [f"{ref} = {value}"]
            mask = 1 << bit
            return [f"{ref} = ({ref} | {mask}) if {value} else ({ref} & {0xFFFF ^ mask})"]
        if type_of(target) == BIT:
            return [f"{self.bind(self.m.bit_writer(target))}({value})"]
        assert not isinstance(target, t.InternalBit)
        return [f"{self.bind(self.m.word_writer(target))}({value})"]

    def store_table(self, target: t.Table, value: str, source: Type) -> list[str]:
        elements = _elements(target)
        out: list[str] = []
        for k, element in enumerate(elements):
            if type_of(target).kind == "bits":
                part = f"(({value} >> {k}) & 1)"
            elif source == WORD:
                part = value
            else:
                part = f"{value}[{k}]"
            out.extend(self.store(element, part, BIT if type_of(element) == BIT else WORD))
        return out

    # --- expressions --------------------------------------------------------------------

    def expr(self, node: t.Expr) -> str:
        self.ops += 1
        if isinstance(node, t.Const):
            return str(node.value)
        if isinstance(node, t.Internal) and node.kind in ("X", "XM"):
            active, steps = self.rt.step_cells(node)
            cells = [f"{self.bind(active)}[{k}]" for k in steps]
            return "(" + " | ".join(cells) + ")" if len(cells) > 1 else cells[0]
        if isinstance(node, t.Internal | t.InternalBit | t.ModuleObj | t.TxtField):
            return self.read(node)
        if isinstance(node, t.Table):
            parts = [self.expr(e) for e in _elements(node)]
            if type_of(node).kind == "bits":
                return "(" + " | ".join(f"({p} << {k})" for k, p in enumerate(parts)) + ")"
            return "[" + ", ".join(parts) + "]"
        if isinstance(node, t.Indexed):
            read_at = self.bind(self.m.indexed_reader(node.base))
            return f"{read_at}({self.expr(node.index)})"
        if isinstance(node, t.Not):
            return f"({self.expr(node.operand)} ^ 1)"
        if isinstance(node, t.Edge):
            return self.edge(node)
        if isinstance(node, t.Compare):
            return _COMPARE[node.op].format(a=self.expr(node.left), b=self.expr(node.right))
        if isinstance(node, t.Shift):
            operand = self.expr(node.operand)
            if node.left:
                return f"(({operand} << {node.count}) & 65535)"
            return f"({operand} >> {node.count})"
        if isinstance(node, t.Bta):
            return f"_bta({self.expr(node.operand)})"
        assert isinstance(node, t.Binary)
        return _WORD_OPS[node.op].format(a=self.expr(node.left), b=self.expr(node.right))

    def read(self, node: t.Internal | t.InternalBit | t.ModuleObj | t.TxtField) -> str:
        # a memory may lend more cells for reading than for writing (the PLC's input
        # images: tsx/plcmemory.py read_cell), read in place, never through a call
        read_cell = getattr(self.m, "read_cell", self.m.cell)
        self.object = node
        cell = read_cell(node)
        if cell is not None:
            table, index, bit = cell
            ref = f"{self.bind(table)}[{index}]"
            return ref if bit is None else f"(({ref} >> {bit}) & 1)"
        if type_of(node) == BIT:
            return f"{self.bind(self.m.bit_reader(node))}()"
        assert not isinstance(node, t.InternalBit)
        return f"{self.bind(self.m.word_reader(node))}()"

    def edge(self, node: t.Edge) -> str:
        # RE/FE: each occurrence compares its bit with the value it had when this
        # occurrence was last evaluated (0 after a cold restart): docs/pl7.md
        edges = self.rt.edges
        k = len(edges)
        edges.append(0)
        read = self.function(["return " + self.expr(node.operand)], "edge")
        rising = node.rising

        def detect() -> int:
            v = read()
            before = edges[k]
            edges[k] = v
            return 1 if (v and not before if rising else before and not v) else 0

        return f"{self.bind(detect)}()"


def _indent(lines: list[str]) -> list[str]:
    return [f"    {line}" for line in lines] or ["    pass"]


def _elements(table: t.Table) -> list[t.Internal | t.ModuleObj]:
    start = table.start
    if isinstance(start, t.Internal):
        return [t.Internal(start.kind, start.index + k) for k in range(table.length)]
    ref = start.ref
    base = ref.index or 0
    return [
        t.ModuleObj(ObjectRef(ref.kind, ref.rack, ref.slot, base + k)) for k in range(table.length)
    ]
