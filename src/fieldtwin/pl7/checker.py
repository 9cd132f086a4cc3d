"""The checker: names resolve, labels exist, called subroutines exist, objects are
inside their tables, and the Grafcet chart's steps and transitions are consistent.

Every refusal is a Pl7Error naming the line, column and token of the culprit.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

from fieldtwin.objects import DATA_WORDS
from fieldtwin.pl7 import tree as t
from fieldtwin.pl7.errors import Pl7Error
from fieldtwin.pl7.printer import format_object


@dataclass(frozen=True, slots=True)
class Limits:
    """The sizes of the PLC's object tables (docs/manual-notes.md, PL7 programs)."""

    bits: int = 4096  # B0..B4095
    words: int = DATA_WORDS  # W0..W4095 (the Text Block tables live there, F-12)
    constant_words: int = DATA_WORDS  # CW0..CW4095
    system_bits: int = 128  # SY0..SY127
    system_words: int = 128  # SW0..SW127
    text_blocks: int = 64  # TXT0..TXT63
    subroutines: int = 256  # SR0..SR255
    steps: int = 256  # steps 0..255 of a chart
    macro_steps: int = 64  # XM0..XM63

    def size(self, kind: str) -> int:
        return {
            "B": self.bits,
            "W": self.words,
            "CW": self.constant_words,
            "SY": self.system_bits,
            "SW": self.system_words,
            "X": self.steps,
            "XM": self.macro_steps,
        }[kind]


DEFAULT_LIMITS = Limits()


def check(program: t.Program, limits: Limits = DEFAULT_LIMITS, source: str = "") -> None:
    _Checker(program, limits, source).run()


class _Checker:
    def __init__(self, program: t.Program, limits: Limits, source: str) -> None:
        self.program = program
        self.limits = limits
        self.source = source
        self.subroutines: set[int] = set()
        self.steps: dict[int, set[str]] = {}

    def fail(self, pos: t.Pos, token: str, expected: str) -> None:
        raise Pl7Error(pos.line, pos.column, token, expected, self.source)

    def run(self) -> None:
        seen: set[str] = set()
        for section in self.program.sections:
            name = section.name if isinstance(section, t.Literal) else "CHART"
            if name in seen:
                self.fail(section.pos, f"%{name}", f"one section %{name} only")
            seen.add(name)
            if isinstance(section, t.Literal) and name.startswith("SR"):
                number = int(name[2:])
                if number >= self.limits.subroutines:
                    self.fail(section.pos, f"%{name}", f"SR0..SR{self.limits.subroutines - 1}")
                self.subroutines.add(number)
        chart = self.program.section("CHART")
        if isinstance(chart, t.Chart):
            self.check_chart(chart)
        for section in self.program.sections:
            if isinstance(section, t.Literal):
                self.check_body(section.sentences)
            else:
                for item in section.items:
                    if isinstance(item, t.StepActions):
                        self.check_body(item.sentences)
                    elif isinstance(item, t.Transition):
                        self.check_expr(item.condition, item.pos)

    # --- Literal -------------------------------------------------------------------

    def check_body(self, items: tuple[t.Sentence | t.Comment, ...]) -> None:
        sentences = [s for s in items if isinstance(s, t.Sentence)]
        labels: set[int] = set()
        for sentence in sentences:
            if sentence.label is not None:
                if sentence.label in labels:
                    self.fail(sentence.pos, f"L{sentence.label}", "a label not used before")
                labels.add(sentence.label)
        for sentence in sentences:
            for action in _actions(sentence.body):
                self.check_action(action, labels, sentence.pos)
            for statement in sentence.body:
                if isinstance(statement, t.If | t.While):
                    self.check_expr(statement.condition, sentence.pos)

    def check_action(self, action: t.Action, labels: set[int], pos: t.Pos) -> None:
        if isinstance(action, t.Jump) and action.label not in labels:
            shown = ", ".join(f"L{n}" for n in sorted(labels)) or "none"
            self.fail(action.pos, f"L{action.label}", f"a label of this section ({shown})")
        elif isinstance(action, t.Call) and action.sr not in self.subroutines:
            shown = ", ".join(f"SR{n}" for n in sorted(self.subroutines)) or "none"
            self.fail(action.pos, f"SR{action.sr}", f"a subroutine of the program ({shown})")
        elif isinstance(action, t.TxtOp):
            self.check_txt(action.index, action.pos)
        elif isinstance(action, t.Assign):
            self.check_expr(action.source, pos)
            for target in action.targets:
                self.check_expr(target, pos)
        elif isinstance(action, t.SetBit | t.Step):
            self.check_expr(action.target, pos)

    def check_txt(self, index: int, pos: t.Pos) -> None:
        if index >= self.limits.text_blocks:
            self.fail(pos, f"TXT{index}", f"a Text Block TXT0..TXT{self.limits.text_blocks - 1}")

    def check_expr(self, node: t.Expr, pos: t.Pos) -> None:
        for obj in _objects(node):
            if isinstance(obj, t.TxtField):
                self.check_txt(obj.index, obj.pos)
            elif isinstance(obj, t.Table):
                start = obj.start
                if isinstance(start, t.Internal):
                    self.check_internal(start, obj.length, obj.pos)
            elif isinstance(obj, t.Indexed):
                self.check_internal(obj.base, 1, obj.pos)
                self.check_internal(obj.index, 1, obj.pos)
            elif isinstance(obj, t.Internal):
                self.check_internal(obj, 1, obj.pos)

    def check_internal(self, obj: t.Internal, length: int, pos: t.Pos) -> None:
        size = self.limits.size(obj.kind)
        shown = format_object(obj) + (f"[{length}]" if length > 1 else "")
        if obj.index + length > size:
            self.fail(pos, shown, f"{obj.kind}0..{obj.kind}{size - 1}")
        if obj.kind == "X" and str(obj.index) not in self.steps.get(t.MAIN, set()):
            self.fail(pos, shown, "a step of the chart (Xi reads step i of %CHART)")
        if obj.kind == "XM" and obj.index not in self.steps:
            self.fail(pos, shown, "a macro-step of the chart (XMj)")

    # --- Grafcet -----------------------------------------------------------------------

    def check_chart(self, chart: t.Chart) -> None:
        items = [i for i in chart.items if not isinstance(i, t.Comment)]
        initial = [i for i in items if isinstance(i, t.Initial)]
        if items and not initial:
            self.fail(chart.pos, "%CHART", "CHART INITIAL n: a chart needs an initial step")
        named: dict[int, set[str]] = {}
        for item in items:
            chart_no = t.MAIN if isinstance(item, t.Initial) else item.chart
            for step in _steps_of(item):
                self.check_step(chart_no, step, item.pos)
                named.setdefault(chart_no, set()).add(step)
        self.steps = named
        self.check_transitions([i for i in items if isinstance(i, t.Transition)])
        self.check_actions([i for i in items if isinstance(i, t.StepActions)])
        self.check_macros(named, chart.pos)

    def check_step(self, chart: int, step: str, pos: t.Pos) -> None:
        if chart == t.MAIN and step in ("IN", "OUT"):
            self.fail(pos, step, "a step number or a macro-step Mj (IN and OUT are in XMj)")
        if chart != t.MAIN and step.startswith("M"):
            self.fail(pos, step, "a step number, IN or OUT (no macro-step inside XMj)")
        if chart != t.MAIN and chart >= self.limits.macro_steps:
            self.fail(pos, f"XM{chart}", f"XM0..XM{self.limits.macro_steps - 1}")
        number = step[1:] if step.startswith("M") else step
        limit = self.limits.macro_steps if step.startswith("M") else self.limits.steps
        if number.isdigit() and int(number) >= limit:
            self.fail(pos, step, f"a step number below {limit}")

    def check_transitions(self, transitions: list[t.Transition]) -> None:
        seen: set[tuple[int, str, str]] = set()
        for tr in transitions:
            key = (tr.chart, tr.source, tr.target)
            shown = f"T: {tr.source}>{tr.target}"
            if key in seen:
                self.fail(tr.pos, shown, "one transition per pair of steps")
            seen.add(key)
            if tr.source == "OUT":
                self.fail(tr.pos, "OUT", "a source step: OUT ends the macro-step")
            if tr.target == "IN":
                self.fail(tr.pos, "IN", "a target step: IN is entered with the macro-step")

    def check_actions(self, actions: list[t.StepActions]) -> None:
        seen: set[tuple[int, str, str]] = set()
        for act in actions:
            shown = f"S({act.kind}){act.step}"
            if act.step.startswith("M"):
                self.fail(act.pos, shown, f"a step: the actions of {act.step} go in X{act.step}")
            key = (act.chart, act.step, act.kind)
            if key in seen:
                self.fail(act.pos, shown, "one action block per step and kind")
            seen.add(key)
        linked = self.linked_steps()
        for act in actions:
            if (act.chart, act.step) not in linked:
                self.fail(act.pos, f"S({act.kind}){act.step}", "a step of a transition or initial")

    def linked_steps(self) -> set[tuple[int, str]]:
        chart = self.program.section("CHART")
        assert isinstance(chart, t.Chart)
        out: set[tuple[int, str]] = set()
        for item in chart.items:
            if isinstance(item, t.Transition):
                out.update({(item.chart, item.source), (item.chart, item.target)})
            elif isinstance(item, t.Initial):
                out.update((t.MAIN, s) for s in item.steps)
        return out

    def check_macros(self, named: dict[int, set[str]], pos: t.Pos) -> None:
        used = {int(s[1:]) for s in named.get(t.MAIN, set()) if s.startswith("M")}
        chart = self.program.section("CHART")
        assert isinstance(chart, t.Chart)
        defined = {i.chart for i in chart.items if isinstance(i, t.Transition | t.StepActions)}
        defined.discard(t.MAIN)
        for j in sorted(used - defined):
            self.fail(pos, f"M{j}", f"an expansion XM{j} (its steps IN .. OUT)")
        for j in sorted(defined - used):
            self.fail(pos, f"XM{j}", f"a macro-step M{j} used in the main chart")
        transitions = [i for i in chart.items if isinstance(i, t.Transition)]
        for j in sorted(defined):
            if not any(tr.chart == j and tr.source == "IN" for tr in transitions):
                self.fail(pos, f"XM{j}", f"a transition XM{j} T: IN>n")
            if not any(tr.chart == j and tr.target == "OUT" for tr in transitions):
                self.fail(pos, f"XM{j}", f"a transition XM{j} T: n>OUT")


def _steps_of(item: t.ChartItem) -> tuple[str, ...]:
    if isinstance(item, t.Initial):
        return item.steps
    if isinstance(item, t.Transition):
        return (item.source, item.target)
    if isinstance(item, t.StepActions):
        return (item.step,)
    return ()


def _actions(body: tuple[t.Statement, ...]) -> Iterator[t.Action]:
    for statement in body:
        if isinstance(statement, t.If):
            yield from statement.then
            yield from statement.otherwise or ()
        elif isinstance(statement, t.While):
            yield from statement.body
        else:
            yield statement


def _objects(node: t.Expr) -> Iterator[t.Expr]:
    yield node
    if isinstance(node, t.Binary | t.Compare):
        yield from _objects(node.left)
        yield from _objects(node.right)
    elif isinstance(node, t.Not | t.Shift | t.Bta | t.Edge):
        yield from _objects(node.operand)
    elif isinstance(node, t.InternalBit):
        yield node.word
