"""The master task of a PL7-3 program: PRE, CHART, POST, once per cycle.

- A Literal-only program is its PRE; subroutines SRi run when called.
- SY0 reads 1 during the first master task after a cold restart, SY1 during the
  first one after a hot restart; the system resets them at the end of that task
  (AEM 2.5-2, 5.1 "processing of a cold restart (setting system bit SY0 to 1)").
- A cold restart clears the internal bits and words and puts the chart in its
  initial situation; a hot restart keeps them (AEM 2.5-2, DEM 2.5-3).
- SY7, the "minutes" system bit (DEM 5.3-1), follows the time given to
  ``run_master_task``: a square wave of period one minute, 1 in its second half.
- A run-time fault (an index out of its table, a Text Block misuse, division by
  zero, a loop past its bound) abandons the sentence in which it happens, sets
  SY18 (FAULT_BIT, docs/manual-notes.md) and is recorded in ``faults``; the task
  goes on with the next sentence.  Nothing is ever raised out of a cycle.
- The task watchdog (docs/pl7.md, docs/manual-notes.md W-1): each master task has a
  budget of ``budget`` operations (the watchdog period at the documented rate of
  OPS_PER_MS operations a millisecond), spent chunk by chunk and at each WHILE pass;
  a task past it is cut where it is, SY11 (WATCHDOG_BIT) is set and ``overrun`` says
  where; no further task runs until a cold or a hot restart.  The loops' own bounds
  (backward JUMPs, WHILE passes, CALL depth) stay program faults; the budget bounds
  what they multiply to.
- Debugging: a breakpoint at a label or a step holds the executor at the end of
  the master task that reached it; ``step()`` runs one master task, ``resume()``
  lets it run again.
- A master task that changed nothing (every object the program sees as it found
  it, no Text Block command, no fault) is a fixed point: while what the program
  sees stays so, the next tasks are counted without being run (``skipped``), with
  the same result (pl7/watch.py; tests/pl7/test_fixed_point.py).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

from fieldtwin.pl7 import tree as t
from fieldtwin.pl7.checker import DEFAULT_LIMITS, Limits, check
from fieldtwin.pl7.compiler import NEXT, RET, Module, compile_body, compile_condition
from fieldtwin.pl7.errors import ObjectRefused, Pl7Error, ProgramFault, WatchdogOverrun
from fieldtwin.pl7.grafcet import ChartLayout, Grafcet
from fieldtwin.pl7.memory import ProgramMemory
from fieldtwin.pl7.parser import parse
from fieldtwin.pl7.watch import Snapshot, WatchedMemory

COLD_RESTART_BIT = 0  # SY0 (AEM 5.1)
HOT_RESTART_BIT = 1  # SY1 (AEM 2.5-2)
MINUTE_BIT = 7  # SY7 "Minutes" system bit (DEM 5.3-1)
WATCHDOG_BIT = 11  # SY11: the master task overran its watchdog (docs/manual-notes.md W-1)
FAULT_BIT = 18  # SY18: a run-time program fault (our reading, docs/manual-notes.md)
WATCHDOG_MS = 150  # the master task's watchdog period (our reading, manual-notes W-1)
OPS_PER_MS = 1000  # operations a TSX 7 processor runs in a millisecond (W-1)
DEFAULT_BUDGET = WATCHDOG_MS * OPS_PER_MS  # operations of one master task
MINUTE_US = 60_000_000
MAX_JUMPS = 10_000  # backward JUMPs in one run of a module before a fault
MAX_CALL_DEPTH = 8  # nested CALLs before a fault
MAX_FAULTS = 32  # faults kept in ``faults`` (the oldest go first)


@dataclass(frozen=True, slots=True)
class FaultRecord:
    """A run-time fault: where (module, line), which master task and why."""

    module: str
    line: int
    cycle: int
    message: str

    def __str__(self) -> str:
        return f"{self.module} line {self.line} (task {self.cycle}): {self.message}"


def budget_of(watchdog_ms: float) -> int:
    """The operations of a master task whose watchdog period is ``watchdog_ms``."""
    return max(1, round(watchdog_ms * OPS_PER_MS))


@dataclass(frozen=True, slots=True)
class Hit:
    """Where a breakpoint held the executor."""

    cycle: int
    module: str = ""
    label: int | None = None
    step: str | None = None

    def __str__(self) -> str:
        if self.step is not None:
            return f"step {self.step} activated in task {self.cycle}"
        return f"{self.module} L{self.label} reached in task {self.cycle}"


class Executor:
    """Runs one checked, compiled program against a ProgramMemory."""

    def __init__(
        self, program: t.Program, memory: ProgramMemory, limits: Limits = DEFAULT_LIMITS
    ) -> None:
        check(program, limits)
        self.program = program
        self.memory = memory
        self.edges: list[int] = []
        self._cycles = 0
        self.faults: deque[FaultRecord] = deque(maxlen=MAX_FAULTS)
        self._held: Hit | None = None
        self.hits: list[Hit] = []
        self._depth = 0
        self.budget = DEFAULT_BUDGET  # operations a master task may run (the watchdog)
        self._budget = [0]  # operations left in the task running (the compiled code's)
        self.overrun: FaultRecord | None = None  # the watchdog tripped: where, which task
        self._label_breaks: dict[str, set[int]] = {}
        self._step_breaks: set[int] = set()
        self._restart_bit: int | None = None
        self._sy = {
            bit: memory.bit_writer(t.Internal("SY", bit))
            for bit in (COLD_RESTART_BIT, HOT_RESTART_BIT, MINUTE_BIT, WATCHDOG_BIT, FAULT_BIT)
        }
        self._minute = self._sy[MINUTE_BIT]
        self.grafcet: Grafcet | None = None
        chart = program.section("CHART")
        if isinstance(chart, t.Chart):
            self.layout: ChartLayout | None = ChartLayout(chart)
            self.grafcet = Grafcet(self.layout, [], {}, {})
        else:
            self.layout = None
        self.modules: dict[str, Module] = {}
        self._subroutines: dict[int, Module] = {}
        self._effects = 0  # Text Block commands, faults and hits so far
        self._skipped = 0  # master tasks counted without being run (a fixed point)
        # a parked master task (fieldtwin.tsx.plc): the idle tasks it owes, counted in
        # ``cycles`` and ``skipped`` when read; ``on_touch`` is told of every change of
        # how the next tasks run (breakpoints, hold, restarts), which wakes it
        self.owed: Callable[[], int] | None = None
        self.on_touch: Callable[[], None] | None = None
        self.skip_idle = True  # False: every task runs (the benchmarks' baseline)
        self._fixed: tuple[object, ...] | None = None  # what a fixed point left
        watched = WatchedMemory(memory, self._effect)
        self._compile(chart, watched)
        self._snapshot: Snapshot | None = None
        if watched.skippable:
            lists, extra = [self.edges], []
            if self.grafcet is not None:
                g = self.grafcet
                lists.append(g.active)
                extra.append(lambda: int(g.pending_initial))
            self._snapshot = watched.snapshot(lists, extra)
        self.cold_restart()

    @classmethod
    def from_source(
        cls, text: str, memory: ProgramMemory, limits: Limits = DEFAULT_LIMITS, source: str = ""
    ) -> Executor:
        program = parse(text, source)
        try:
            return cls(program, memory, limits)
        except ObjectRefused as err:  # where the object stands on its line
            lines = text.splitlines()
            line = lines[err.line - 1] if 0 < err.line <= len(lines) else ""
            column = line.upper().find(err.token.upper()) + 1 if err.token else 0
            raise Pl7Error(
                err.line, max(column, 1), err.token, f"an object the PLC has ({err.reason})", source
            ) from None
        except Pl7Error as err:
            if source and not err.source:
                raise Pl7Error(
                    err.line, err.column, err.token, err.expected, source, said=err.said
                ) from None
            raise

    @property
    def cycles(self) -> int:
        """Master tasks so far (run or skipped)."""
        owed = self.owed
        return self._cycles if owed is None else self._cycles + owed()

    @property
    def skipped(self) -> int:
        """Master tasks counted without being run: a fixed point (pl7/watch.py)."""
        owed = self.owed
        return self._skipped if owed is None else self._skipped + owed()

    def count_idle(self, tasks: int) -> None:
        """``tasks`` master tasks that would each have been skipped (a parked task)."""
        self._cycles += tasks
        self._skipped += tasks

    @property
    def held(self) -> Hit | None:
        """Where a breakpoint (or the console) holds the executor, or None."""
        return self._held

    @held.setter
    def held(self, hit: Hit | None) -> None:
        self._touch()
        self._held = hit

    def _touch(self) -> None:
        if self.on_touch is not None:
            self.on_touch()

    @property
    def budget_cell(self) -> list[int]:
        return self._budget

    def _effect(self) -> None:
        self._effects += 1

    def _compile(self, chart: t.Section | None, memory: WatchedMemory) -> None:
        for section in self.program.sections:
            if isinstance(section, t.Literal):
                module = compile_body(section.name, section.sentences, memory, self)
                self.modules[section.name] = module
                if section.name.startswith("SR"):
                    self._subroutines[int(section.name[2:])] = module
        if self.grafcet is None or self.layout is None or not isinstance(chart, t.Chart):
            return
        layout, g = self.layout, self.grafcet
        for item in chart.items:
            if isinstance(item, t.Transition):
                condition = compile_condition(item.condition, memory, self)
                source = layout.exit(item.chart, item.source)
                target = layout.entry(item.chart, item.target)
                g.transitions.append((source, target, condition, item.pos.line))
            elif isinstance(item, t.StepActions):
                prefix = "CHART" if item.chart == t.MAIN else f"XM{item.chart}"
                name = f"{prefix} S({item.kind}){item.step}"
                module = compile_body(name, item.sentences, memory, self)
                table = g.on_activation if item.kind == "A" else g.on_deactivation
                table[layout.index[(item.chart, item.step)]] = module

    # --- Runtime (for the compiled code) ---------------------------------------------

    def step_cells(self, obj: t.Internal) -> tuple[list[int], tuple[int, ...]]:
        """Xi: the activity of step i; XMj: of every step of the expansion XMj."""
        assert self.layout is not None and self.grafcet is not None
        if obj.kind == "X":
            return self.grafcet.active, (self.layout.index[(t.MAIN, str(obj.index))],)
        return self.grafcet.active, tuple(self.layout.macro_steps(obj.index))

    def call(self, sr: int) -> None:
        if self._depth >= MAX_CALL_DEPTH:
            raise ProgramFault(f"CALL SR{sr}: more than {MAX_CALL_DEPTH} nested calls")
        self._depth += 1
        try:
            self.run_module(self._subroutines[sr])
        finally:
            self._depth -= 1

    def run_module(self, module: Module) -> None:
        code, costs, n = module.code, module.costs, len(module.code)
        budget = self._budget
        i = jumps = 0
        while i < n:
            budget[0] -= costs[i]
            if budget[0] < 0:
                raise WatchdogOverrun(module.name, module.lines[i])
            r = code[i]()  # faults are caught, sentence by sentence, inside the chunk
            if r == NEXT:
                i += 1
            elif r == RET:
                return
            else:
                if r <= i:
                    jumps += 1
                    if jumps > MAX_JUMPS:
                        message = f"more than {MAX_JUMPS} backward JUMPs in one run"
                        self.fault(module.name, module.lines[i], ProgramFault(message))
                        return
                i = r

    def watch(self, module: str) -> set[int]:
        return self._label_breaks.setdefault(module, set())

    def hit(self, module: str, label: int) -> None:
        self._effects += 1
        self._hit(Hit(self._cycles, module, label))

    def fault(self, module: str, line: int, err: ProgramFault) -> None:
        self._effects += 1
        self.faults.append(FaultRecord(module, line, self._cycles, str(err)))
        self._sy[FAULT_BIT](1)

    # --- the master task ---------------------------------------------------------------

    def cold_restart(self) -> None:
        """Internal bits and words cleared, edges forgotten, chart to its initial steps."""
        self._touch()
        self.memory.clear_internal()
        self.edges[:] = [0] * len(self.edges)
        if self.grafcet is not None:
            self.grafcet.reset()
        self.faults.clear()
        self._sy[FAULT_BIT](0)
        self._sy[WATCHDOG_BIT](0)
        self.overrun = None
        self._restart_bit = COLD_RESTART_BIT
        self._fixed = None

    def hot_restart(self) -> None:
        """Everything kept (SY11 too, after a watchdog); SY1 reads 1 during the next task."""
        self._touch()
        self.overrun = None
        self._restart_bit = HOT_RESTART_BIT
        self._fixed = None

    def run_master_task(self, now_us: int | None = None) -> bool:
        """One master task (PRE, CHART, POST) unless a breakpoint holds the executor
        or the watchdog tripped (until a cold or a hot restart)."""
        if self._held is not None or self.overrun is not None:
            return False
        self._task(now_us)
        return True

    def step(self, now_us: int | None = None) -> None:
        """Debugging: one master task, then hold again."""
        if self.overrun is not None:
            return
        self.held = None
        self._task(now_us)
        if self._held is None:
            self._held = Hit(self.cycles)

    def resume(self) -> None:
        self.held = None

    def _task(self, now_us: int | None) -> None:
        self._cycles += 1
        restart = self._restart_bit
        if restart is not None:
            self._sy[restart](1)
        if now_us is not None:
            self._minute(1 if now_us % MINUTE_US >= MINUTE_US // 2 else 0)
        snapshot = self._snapshot
        if (
            snapshot is None
            or restart is not None
            or not self.skip_idle
            or self._step_breaks
            or any(self._label_breaks.values())  # _breakpoints(), inline
        ):
            self._fixed = None
            self._sections()
        else:
            before = snapshot()
            if before == self._fixed:  # the same as after a task that changed nothing
                self._skipped += 1
                return
            effects = self._effects
            self._sections()
            after = snapshot()
            self._fixed = after if after == before and self._effects == effects else None
        if restart is not None:
            self._sy[restart](0)
            self._restart_bit = None

    def _breakpoints(self) -> bool:
        return bool(self._step_breaks) or any(self._label_breaks.values())

    def _sections(self) -> None:
        self._budget[0] = self.budget
        try:
            self._run_sections()
        except WatchdogOverrun as over:  # the task is cut where it is
            self._effects += 1
            message = f"master task exceeded {self.budget} operations (the watchdog)"
            self.overrun = FaultRecord(over.module, over.line, self._cycles, message)
            self._sy[WATCHDOG_BIT](1)

    def _run_sections(self) -> None:
        pre = self.modules.get("PRE")
        if pre is not None:
            self.run_module(pre)
        g = self.grafcet
        if g is not None:
            g.evolve(self.run_module, self.fault)
            if self._step_breaks:
                for k in g.activated:
                    if k in self._step_breaks:
                        self._hit(Hit(self._cycles, step=str(g.layout.nodes[k])))
        post = self.modules.get("POST")
        if post is not None:
            self.run_module(post)

    # --- debugging ----------------------------------------------------------------------

    def break_at_label(self, module: str, label: int) -> None:
        compiled = self.modules.get(module)
        if compiled is None or label not in compiled.labels:
            raise Pl7Error(0, 0, f"{module} L{label}", "a label of a Literal section")
        self._touch()
        self.watch(module).add(label)

    def break_at_step(self, step: str) -> None:
        if self.layout is None:
            raise Pl7Error(0, 0, step, "a step of the chart (the program has no CHART)")
        names = {str(node): k for k, node in enumerate(self.layout.nodes)}
        if step not in names:
            raise Pl7Error(0, 0, step, "a step of the chart: " + ", ".join(names))
        self._touch()
        self._step_breaks.add(names[step])

    def clear_breakpoints(self) -> None:
        self._touch()
        for labels in self._label_breaks.values():
            labels.clear()  # the compiled chunks keep these sets
        self._step_breaks.clear()

    def _hit(self, hit: Hit) -> None:
        self.hits.append(hit)
        del self.hits[:-MAX_FAULTS]
        if self._held is None:
            self._held = hit

    # --- state ---------------------------------------------------------------------------

    def active_steps(self) -> list[str]:
        return [] if self.grafcet is None else self.grafcet.active_steps()

    def step_active(self, step: str) -> bool:
        if self.layout is None or self.grafcet is None:
            return False
        for k, node in enumerate(self.layout.nodes):
            if str(node) == step:
                return bool(self.grafcet.active[k])
        raise Pl7Error(0, 0, step, "a step of the chart")
