"""A tree-walking reference evaluator of PL7-3: the language's semantics, slowly.

The executor (pl7/executor.py) compiles each program into Python once and runs the
generated code; that code is fast but was its own only semantics.  ``Reference``
walks the same checked tree at every master task instead, against the same
``ProgramMemory`` (through its readers and writers, never through cells), with the
same bounds and faults (docs/pl7.md, "Run-time faults", "The task watchdog"), and
without any shortcut (no idle task is skipped).  tests/pl7/test_reference.py runs
both on generated programs and compares the memory after every master task.

It is meant for tests and for checking shortcuts, not for running a plant: it is
roughly two orders of magnitude slower than the compiled code.  No debugging
(breakpoints) here.

Written from docs/pl7.md and the chart's evolution rules (pl7/grafcet.py's
docstring), not from the compiler; the two share only the tree, the checker, the
memory and the chart's layout (which step is which index).
"""

from __future__ import annotations

import dataclasses
from collections import deque
from typing import Any

from fieldtwin.objects import ObjectRef
from fieldtwin.pl7 import tree as t
from fieldtwin.pl7.checker import DEFAULT_LIMITS, Limits, check
from fieldtwin.pl7.compiler import MAX_WHILE, type_of
from fieldtwin.pl7.errors import ProgramFault, WatchdogOverrun
from fieldtwin.pl7.executor import (
    COLD_RESTART_BIT,
    DEFAULT_BUDGET,
    FAULT_BIT,
    HOT_RESTART_BIT,
    MAX_CALL_DEPTH,
    MAX_FAULTS,
    MAX_JUMPS,
    MINUTE_BIT,
    MINUTE_US,
    WATCHDOG_BIT,
    FaultRecord,
)
from fieldtwin.pl7.grafcet import ChartLayout
from fieldtwin.pl7.memory import ProgramMemory
from fieldtwin.pl7.types import BIT

Value = Any  # 0/1, a word 0..65535, a bit-string mask or a list of words


class _Jump(Exception):  # control flow, not an error
    def __init__(self, label: int) -> None:
        self.label = label


class _Return(Exception):
    pass


def _fresh(node: Any) -> Any:
    """The tree rebuilt so that no node object is shared: each RE/FE occurrence is
    then its own object, and its memory can be kept by identity."""
    if isinstance(node, tuple):
        return tuple(_fresh(x) for x in node)
    if dataclasses.is_dataclass(node) and not isinstance(node, type | ObjectRef | t.Pos):
        values = {f.name: _fresh(getattr(node, f.name)) for f in dataclasses.fields(node)}
        return type(node)(**values)
    return node


def signed(v: int) -> int:
    return v - 0x10000 if v >= 0x8000 else v


def word(v: int) -> int:
    return v % 0x10000


def _towards_zero(x: int, y: int) -> int:
    q = abs(x) // abs(y)
    return q if (x >= 0) == (y > 0) else -q


def bta(v: int) -> list[int]:
    """BTA: sign and five digits, two characters a word, the first in the low byte."""
    text = ("-" if signed(v) < 0 else "+") + str(abs(signed(v))).rjust(5, "0")
    codes = [ord(ch) for ch in text]
    return [codes[0] + 256 * codes[1], codes[2] + 256 * codes[3], codes[4] + 256 * codes[5]]


# --- the task watchdog's cost model (docs/pl7.md, "The task watchdog") -------------
# One operation per instruction, object read or written, operator and comparison; an
# IF counts its condition and both branches; a statement of a sentence counts one
# more than the same action inside an IF or a WHILE (the count the compiled code
# makes); a table counts each of its elements; RE/FE count themselves and their bit.


def expr_cost(node: t.Expr) -> int:
    if isinstance(node, t.Table):
        return 1 + node.length
    if isinstance(node, t.Indexed):
        return 2
    if isinstance(node, t.Not | t.Edge | t.Shift | t.Bta):
        inner = node.operand
        return 1 + expr_cost(inner)
    if isinstance(node, t.Compare | t.Binary):
        return 1 + expr_cost(node.left) + expr_cost(node.right)
    return 1  # a constant or an object


def store_cost(target: t.Expr) -> int:
    if isinstance(target, t.Table):
        return 1 + target.length
    if isinstance(target, t.Indexed):
        return 2
    return 1


def action_cost(node: t.Action) -> int:
    if isinstance(node, t.Assign):
        return 1 + expr_cost(node.source) + sum(store_cost(x) for x in node.targets)
    if isinstance(node, t.SetBit):
        return 1 + store_cost(node.target)
    if isinstance(node, t.Step):
        return 1 + expr_cost(node.target) + store_cost(node.target)
    return 1


def while_pass_cost(node: t.While) -> int:
    """What each pass of a WHILE after the first spends."""
    return 1 + expr_cost(node.condition) + sum(action_cost(a) for a in node.body)


def statement_cost(node: t.Statement) -> int:
    if isinstance(node, t.If):
        branches = node.then + (node.otherwise or ())
        return 1 + expr_cost(node.condition) + sum(action_cost(a) for a in branches)
    if isinstance(node, t.While):
        return while_pass_cost(node)
    return 1 + action_cost(node)


def chunk_cost(sentences: list[t.Sentence]) -> int:
    return max(1, sum(statement_cost(s) for x in sentences for s in x.body))


class _Body:
    """A Literal body cut into chunks: a chunk starts at every sentence a JUMP lands
    on; the budget is spent a chunk at a time, before it runs."""

    def __init__(self, name: str, items: tuple[t.Sentence | t.Comment, ...]) -> None:
        self.name = name
        sentences = [s for s in items if isinstance(s, t.Sentence)]
        landing = set()
        for s in sentences:
            for statement in s.body:
                for a in _actions(statement):
                    if isinstance(a, t.Jump):
                        landing.add(a.label)
        self.chunks: list[list[t.Sentence]] = []
        for s in sentences:
            if not self.chunks or s.label in landing:
                self.chunks.append([])
            self.chunks[-1].append(s)
        self.costs = [chunk_cost(c) for c in self.chunks]
        self.at = {c[0].label: k for k, c in enumerate(self.chunks) if c[0].label is not None}


def _actions(statement: t.Statement) -> tuple[t.Action, ...]:
    if isinstance(statement, t.If):
        return statement.then + (statement.otherwise or ())
    if isinstance(statement, t.While):
        return statement.body
    return (statement,)


class Reference:
    """Runs a checked program by walking its tree; the Executor's public state
    (``cycles``, ``faults``, ``overrun``, ``budget``, ``active_steps``) and restarts."""

    def __init__(
        self, program: t.Program, memory: ProgramMemory, limits: Limits = DEFAULT_LIMITS
    ) -> None:
        check(program, limits)
        self.program: t.Program = _fresh(program)
        self.memory = memory
        self.cycles = 0
        self.faults: deque[FaultRecord] = deque(maxlen=MAX_FAULTS)
        self.overrun: FaultRecord | None = None
        self.budget = DEFAULT_BUDGET
        self._left = 0
        self._depth = 0
        self._restart: int | None = None
        self._edges: dict[int, int] = {}  # id(Edge) -> its bit when last evaluated
        self.bodies: dict[str, _Body] = {}
        self.layout: ChartLayout | None = None
        self.active: list[int] = []
        self._initial_pending = False
        self._transitions: list[t.Transition] = []
        self._step_bodies: dict[tuple[str, int], _Body] = {}
        for section in self.program.sections:
            if isinstance(section, t.Literal):
                self.bodies[section.name] = _Body(section.name, section.sentences)
            else:
                self._chart(section)
        self.cold_restart()

    def _chart(self, chart: t.Chart) -> None:
        self.layout = layout = ChartLayout(chart)
        self.active = [0] * len(layout.nodes)
        for item in chart.items:
            if isinstance(item, t.Transition):
                self._transitions.append(item)
            elif isinstance(item, t.StepActions):
                prefix = "CHART" if item.chart == t.MAIN else f"XM{item.chart}"
                name = f"{prefix} S({item.kind}){item.step}"
                k = layout.index[(item.chart, item.step)]
                self._step_bodies[(item.kind, k)] = _Body(name, item.sentences)

    # --- restarts and the master task ------------------------------------------------

    def cold_restart(self) -> None:
        self.memory.clear_internal()
        self._edges.clear()
        self.active[:] = [0] * len(self.active)
        self._initial_pending = self.layout is not None
        self.faults.clear()
        self._sy(FAULT_BIT, 0)
        self._sy(WATCHDOG_BIT, 0)
        self.overrun = None
        self._restart = COLD_RESTART_BIT

    def hot_restart(self) -> None:
        self.overrun = None
        self._restart = HOT_RESTART_BIT

    def _sy(self, bit: int, value: int) -> None:
        self.memory.bit_writer(t.Internal("SY", bit))(value)

    def run_master_task(self, now_us: int | None = None) -> bool:
        if self.overrun is not None:
            return False
        self.cycles += 1
        if self._restart is not None:
            self._sy(self._restart, 1)
        if now_us is not None:
            self._sy(MINUTE_BIT, int(now_us % MINUTE_US >= MINUTE_US // 2))
        self._left = self.budget
        try:
            for name in ("PRE", "CHART", "POST"):
                if name == "CHART":
                    if self.layout is not None:
                        self._evolve()
                elif name in self.bodies:
                    self._run(self.bodies[name])
        except WatchdogOverrun as over:
            message = f"master task exceeded {self.budget} operations (the watchdog)"
            self.overrun = FaultRecord(over.module, over.line, self.cycles, message)
            self._sy(WATCHDOG_BIT, 1)
        if self._restart is not None:
            self._sy(self._restart, 0)
            self._restart = None
        return True

    def active_steps(self) -> list[str]:
        if self.layout is None:
            return []
        return [str(n) for n, a in zip(self.layout.nodes, self.active, strict=True) if a]

    def _fault(self, module: str, line: int, message: str) -> None:
        self.faults.append(FaultRecord(module, line, self.cycles, message))
        self._sy(FAULT_BIT, 1)

    # --- the chart ---------------------------------------------------------------------

    def _evolve(self) -> None:
        layout = self.layout
        assert layout is not None
        if self._initial_pending:
            self._initial_pending = False
            entered = sorted(set(layout.initial))
            for k in entered:
                self.active[k] = 1
            self._step_actions([], entered)
            return
        before = list(self.active)
        fired: list[tuple[int, int]] = []
        for tr in self._transitions:
            source = layout.exit(tr.chart, tr.source)
            if not before[source]:
                continue
            try:
                fire = self._eval(tr.condition)
            except ProgramFault as err:
                self._fault("CHART", tr.pos.line, str(err))
                fire = 0
            if fire:
                fired.append((source, layout.entry(tr.chart, tr.target)))
        if not fired:
            return
        sources = {s for s, _ in fired}
        targets = {d for _, d in fired}
        left = sorted(sources - targets)
        entered = sorted(k for k in targets if not before[k])
        for k in left:
            self.active[k] = 0
        for k in entered:
            self.active[k] = 1
        self._step_actions(left, entered)

    def _step_actions(self, left: list[int], entered: list[int]) -> None:
        for kind, steps in (("D", left), ("A", entered)):
            for k in steps:
                body = self._step_bodies.get((kind, k))
                if body is not None:
                    self._run(body)

    # --- Literal bodies ---------------------------------------------------------------

    def _run(self, body: _Body) -> None:
        i = backward = 0
        while i < len(body.chunks):
            self._left -= body.costs[i]
            if self._left < 0:
                raise WatchdogOverrun(body.name, body.chunks[i][0].pos.line)
            goto = self._chunk(body, body.chunks[i])
            if goto is None:
                i += 1
            elif goto < 0:
                return
            else:
                if goto <= i:
                    backward += 1
                    if backward > MAX_JUMPS:
                        message = f"more than {MAX_JUMPS} backward JUMPs in one run"
                        self._fault(body.name, body.chunks[i][0].pos.line, message)
                        return
                i = goto

    def _chunk(self, body: _Body, sentences: list[t.Sentence]) -> int | None:
        """None: the next chunk; -1: RET; else the chunk a JUMP goes to."""
        for sentence in sentences:
            try:
                for statement in sentence.body:
                    self._statement(statement, body.name, sentence.pos.line)
            except ProgramFault as err:
                self._fault(body.name, sentence.pos.line, str(err))
            except _Jump as jump:
                return body.at[jump.label]
            except _Return:
                return -1
        return None

    def _statement(self, node: t.Statement, module: str, line: int) -> None:
        if isinstance(node, t.If):
            branch = node.then if self._eval(node.condition) else node.otherwise
            for action in branch or ():
                self._action(action)
        elif isinstance(node, t.While):
            passes = 0
            while self._eval(node.condition):
                passes += 1
                if passes > MAX_WHILE:
                    raise ProgramFault(f"WHILE did not end within {MAX_WHILE} iterations")
                if passes > 1:
                    self._left -= while_pass_cost(node)
                    if self._left < 0:
                        raise WatchdogOverrun(module, line)
                for action in node.body:
                    self._action(action)
        else:
            self._action(node)

    def _action(self, node: t.Action) -> None:
        m = self.memory
        if isinstance(node, t.Assign):
            value = self._eval(node.source)
            kind = type_of(node.source)
            for target in node.targets:
                self._store(target, value, kind.kind)
        elif isinstance(node, t.SetBit):
            self._store(node.target, int(node.value), "bit")
        elif isinstance(node, t.Step):
            self._store(node.target, word(self._eval(node.target) + (1 if node.up else -1)), "word")
        elif isinstance(node, t.TxtOp):
            if node.op == "RESET":
                m.txt_reset(node.index)
            else:
                m.txt_start(node.index, node.op)
        elif isinstance(node, t.Jump):
            raise _Jump(node.label)
        elif isinstance(node, t.Call):
            if self._depth >= MAX_CALL_DEPTH:
                raise ProgramFault(f"CALL SR{node.sr}: more than {MAX_CALL_DEPTH} nested calls")
            self._depth += 1
            try:
                self._run(self.bodies[f"SR{node.sr}"])
            finally:
                self._depth -= 1
        else:
            raise _Return

    def _store(self, target: t.Expr, value: Value, kind: str) -> None:
        """``value`` of kind bit, word, bits (a mask) or words (a list) into ``target``."""
        m = self.memory
        if isinstance(target, t.Table):
            for k, element in enumerate(_elements(target)):
                if type_of(target).kind == "bits":
                    self._store(element, (value >> k) & 1, "bit")
                elif kind == "words":
                    self._store(element, value[k], "word")
                else:
                    self._store(element, value, "word")
        elif isinstance(target, t.Indexed):
            m.indexed_writer(target.base)(self._eval(target.index), value)
        elif isinstance(target, t.Internal | t.InternalBit | t.ModuleObj | t.TxtField):
            if type_of(target) == BIT:
                m.bit_writer(target)(value)
            else:
                assert not isinstance(target, t.InternalBit)
                m.word_writer(target)(value)

    # --- expressions ------------------------------------------------------------------

    def _eval(self, node: t.Expr) -> Value:
        m = self.memory
        if isinstance(node, t.Const):
            return node.value
        if isinstance(node, t.Internal) and node.kind in ("X", "XM"):
            assert self.layout is not None
            if node.kind == "X":
                return self.active[self.layout.index[(t.MAIN, str(node.index))]]
            return int(any(self.active[k] for k in self.layout.macro_steps(node.index)))
        if isinstance(node, t.Internal | t.InternalBit | t.ModuleObj | t.TxtField):
            if type_of(node) == BIT:
                return m.bit_reader(node)()
            assert not isinstance(node, t.InternalBit)
            return m.word_reader(node)()
        if isinstance(node, t.Table):
            values = [self._eval(e) for e in _elements(node)]
            if type_of(node).kind == "bits":
                return sum(v << k for k, v in enumerate(values))
            return values
        if isinstance(node, t.Indexed):
            return m.indexed_reader(node.base)(self._eval(node.index))
        if isinstance(node, t.Not):
            return 1 - self._eval(node.operand)
        if isinstance(node, t.Edge):
            now = self._eval(node.operand)
            was = self._edges.get(id(node), 0)
            self._edges[id(node)] = now
            return int(now > was) if node.rising else int(now < was)
        if isinstance(node, t.Compare):
            a, b = signed(self._eval(node.left)), signed(self._eval(node.right))
            result = {
                "=": a == b,
                "<>": a != b,
                "<": a < b,
                ">": a > b,
                "<=": a <= b,
                ">=": a >= b,
            }[node.op]
            return int(result)
        if isinstance(node, t.Shift):
            v = self._eval(node.operand)
            return word(v * 2**node.count) if node.left else v // 2**node.count
        if isinstance(node, t.Bta):
            return bta(self._eval(node.operand))
        assert isinstance(node, t.Binary)
        return _binary(node.op, self._eval(node.left), self._eval(node.right))


def _binary(op: t.Op, a: int, b: int) -> int:
    if op in (t.Op.AND, t.Op.WAND):
        return a & b
    if op in (t.Op.OR, t.Op.WOR):
        return a | b
    if op is t.Op.WXOR:
        return a ^ b
    x, y = signed(a), signed(b)
    if op is t.Op.ADD:
        return word(x + y)
    if op is t.Op.SUB:
        return word(x - y)
    if op is t.Op.MUL:
        return word(x * y)
    if y == 0:
        raise ProgramFault("division by zero" if op is t.Op.DIV else "REM by zero")
    if op is t.Op.DIV:
        return word(_towards_zero(x, y))
    remainder = abs(x) % abs(y)  # REM: the sign of the dividend
    return word(-remainder if x < 0 else remainder)


def _elements(table: t.Table) -> list[t.Internal | t.ModuleObj]:
    start = table.start
    if isinstance(start, t.Internal):
        return [t.Internal(start.kind, start.index + k) for k in range(table.length)]
    ref = start.ref
    return [
        t.ModuleObj(ObjectRef(ref.kind, ref.rack, ref.slot, (ref.index or 0) + k))
        for k in range(table.length)
    ]
