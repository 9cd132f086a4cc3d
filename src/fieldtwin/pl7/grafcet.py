"""The CHART: steps, transitions and macro-steps as the DEM 5.3-4 listing writes them.

Evolution rules (one evolution per master task, docs/pl7.md):
- a transition is enabled when its source step is active; it fires when it is
  enabled and its condition is true; all transitions that can fire fire together;
- firing deactivates the source steps and activates the target steps; a step
  both deactivated and activated stays active and runs neither block;
- the S(D) blocks of the steps deactivated run, then the S(A) blocks of the steps
  activated, each in the order of the chart's steps;
- a macro-step Mj entered activates the step IN of its expansion XMj; a transition
  leaving Mj is enabled when the step OUT of XMj is active, and deactivates it;
  XMj reads 1 while any step of the expansion is active.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from fieldtwin.pl7 import tree as t
from fieldtwin.pl7.compiler import Module
from fieldtwin.pl7.errors import ProgramFault
from fieldtwin.pl7.memory import Reader


@dataclass(frozen=True, slots=True)
class StepNode:
    chart: int
    name: str

    def __str__(self) -> str:
        return self.name if self.chart == t.MAIN else f"XM{self.chart},{self.name}"


def step_order(chart: int, name: str) -> tuple[int, int, int]:
    rank = {"IN": -1, "OUT": 1_000_000}.get(name, 0)
    number = int(name) if name.isdigit() else 0
    return (chart, rank, number)


class ChartLayout:
    """The steps of a chart as indexes into one activity list."""

    def __init__(self, chart: t.Chart) -> None:
        names: set[tuple[int, str]] = set()
        for item in chart.items:
            if isinstance(item, t.Transition):
                names.update({(item.chart, item.source), (item.chart, item.target)})
            elif isinstance(item, t.StepActions):
                names.add((item.chart, item.step))
            elif isinstance(item, t.Initial):
                names.update((t.MAIN, s) for s in item.steps)
        real: set[tuple[int, str]] = set()
        for chart_no, name in names:
            if chart_no == t.MAIN and name.startswith("M"):
                macro = int(name[1:])
                real.update({(macro, "IN"), (macro, "OUT")})
            else:
                real.add((chart_no, name))
        ordered = sorted(real, key=lambda cn: step_order(*cn))
        self.nodes = [StepNode(c, n) for c, n in ordered]
        self.index = {(c, n): k for k, (c, n) in enumerate(ordered)}
        self.initial = [
            self.entry(t.MAIN, s) for i in chart.items if isinstance(i, t.Initial) for s in i.steps
        ]

    def entry(self, chart: int, name: str) -> int:
        """The step a transition enters: IN of XMj for the macro-step Mj."""
        if chart == t.MAIN and name.startswith("M"):
            return self.index[(int(name[1:]), "IN")]
        return self.index[(chart, name)]

    def exit(self, chart: int, name: str) -> int:
        """The step a transition leaves: OUT of XMj for the macro-step Mj."""
        if chart == t.MAIN and name.startswith("M"):
            return self.index[(int(name[1:]), "OUT")]
        return self.index[(chart, name)]

    def macro_steps(self, macro: int) -> list[int]:
        return [k for k, node in enumerate(self.nodes) if node.chart == macro]


RunModule = Callable[[Module], None]
Fault = Callable[[str, int, ProgramFault], None]


class Grafcet:
    """The activity of the chart's steps and its evolution."""

    def __init__(
        self,
        layout: ChartLayout,
        transitions: list[tuple[int, int, Reader, int]],
        on_activation: dict[int, Module],
        on_deactivation: dict[int, Module],
    ) -> None:
        self.layout = layout
        self.active = [0] * len(layout.nodes)
        self.transitions = transitions  # (source, target, condition, line)
        self.on_activation = on_activation
        self.on_deactivation = on_deactivation
        self.pending_initial = True
        self.activated: list[int] = []  # the steps activated by the last evolution

    def reset(self) -> None:
        """A cold restart: the initial situation is entered at the next CHART."""
        self.active[:] = [0] * len(self.active)
        self.pending_initial = True

    def evolve(self, run: RunModule, fault: Fault) -> None:
        active = self.active
        if self.pending_initial:
            self.pending_initial = False
            entered = sorted(set(self.layout.initial))
            for k in entered:
                active[k] = 1
            self._actions([], entered, run)
            return
        sources: list[int] = []
        targets: list[int] = []
        for source, target, condition, line in self.transitions:
            if active[source]:
                try:
                    fire = condition()
                except ProgramFault as err:
                    fault("CHART", line, err)
                    fire = 0
                if fire:
                    sources.append(source)
                    targets.append(target)
        if not sources:
            self.activated = []
            return
        entered = sorted({k for k in targets if not active[k]})
        left = sorted(set(sources) - set(targets))
        for k in left:
            active[k] = 0
        for k in entered:
            active[k] = 1
        self._actions(left, entered, run)

    def _actions(self, left: list[int], entered: list[int], run: RunModule) -> None:
        self.activated = entered
        for k in left:
            module = self.on_deactivation.get(k)
            if module is not None:
                run(module)
        for k in entered:
            module = self.on_activation.get(k)
            if module is not None:
                run(module)

    def active_steps(self) -> list[str]:
        return [str(node) for node, a in zip(self.layout.nodes, self.active, strict=True) if a]
