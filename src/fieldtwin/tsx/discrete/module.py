"""Discrete input and output modules: 16 points seen by the program (Ixy,0..F)."""

from __future__ import annotations

from collections.abc import Callable
from typing import ClassVar

from fieldtwin.clock import MS
from fieldtwin.errors import ConfigError
from fieldtwin.signals import DiscreteSignal
from fieldtwin.tsx.bus import ModuleState
from fieldtwin.tsx.module import IntelligentModule

POINTS = 16  # object bits 0..F (fieldtwin.tsx.addressing)


class DiscreteInputs(IntelligentModule):
    """An input module: ``set_input(i, level)``; Ixy,i follows it at once."""

    type_name: ClassVar[str] = "TSX DET"
    self_test_us: ClassVar[int] = 1 * MS
    has_run_stop: ClassVar[bool] = False
    points: ClassVar[int] = POINTS
    shows_o_bits: ClassVar[bool] = False

    def __init__(self, *args: object, **kwargs: object) -> None:
        super().__init__(*args, **kwargs)  # type: ignore[arg-type]
        self.levels = 0
        self.signals: dict[int, DiscreteSignal] = {}

    def set_input(self, point: int, level: bool) -> None:
        """A constant level on input ``point`` (a signal there is dropped)."""
        self._check(point)
        self.signals.pop(point, None)
        self._level(point, level)

    def drive(self, point: int, signal: DiscreteSignal) -> None:
        """Input ``point`` follows ``signal`` (simulated time)."""
        self._check(point)
        self.signals[point] = signal
        self._follow(point, signal, self.clock.now)

    def _follow(self, point: int, signal: DiscreteSignal, now: int) -> None:
        if self.signals.get(point) is not signal:
            return
        self._level(point, signal.value_at(now))
        after = signal.next_change(now)
        if after is not None:
            self.call_at(after, lambda at: self._follow(point, signal, at))

    def _check(self, point: int) -> None:
        if not 0 <= point < self.points:
            raise ConfigError(
                f"{self.type_name} {self.address}: no input {point} (allowed: 0..{self.points - 1})"
            )

    def _level(self, point: int, level: bool) -> None:
        mask = 1 << point
        self.levels = (self.levels | mask) if level else (self.levels & ~mask)
        if self.state is ModuleState.OPERATIONAL:
            self.i_bits = self.levels

    def on_self_test_done(self, now: int) -> None:
        self.i_bits = self.levels


class DiscreteOutputs(IntelligentModule):
    """An output module: Oxy,0..Oxy,F as the PLC wrote them (``o_bits``)."""

    type_name: ClassVar[str] = "TSX DST"
    self_test_us: ClassVar[int] = 1 * MS
    has_run_stop: ClassVar[bool] = False
    discrete_outputs: ClassVar[int] = POINTS
    shows_i_bits: ClassVar[bool] = False

    def __init__(self, *args: object, **kwargs: object) -> None:
        super().__init__(*args, **kwargs)  # type: ignore[arg-type]
        self.wires: dict[int, list[Callable[[bool], None]]] = {}

    def output(self, point: int) -> int:
        return (self.o_bits >> point) & 1

    def wire(self, point: int, receiver: Callable[[bool], None]) -> None:
        """Wire output ``point`` to an input elsewhere (the DEM 5.3-4 O3,4 drives the
        DEM's synchronization input): ``receiver(level)`` on every change."""
        if not 0 <= point < self.discrete_outputs:
            raise ConfigError(f"{self.type_name} {self.address}: no output {point:X}")
        self.wires.setdefault(point, []).append(receiver)

    def on_outputs(self, old_ow: list[int], old_o: int, now: int) -> None:
        changed = old_o ^ self.o_bits
        for point, receivers in self.wires.items():
            if changed >> point & 1:
                for receiver in receivers:
                    receiver(bool(self.o_bits >> point & 1))


INPUT_REFERENCES = {"TSX DET 805": 8, "TSX DET 1605": 16, "TSX DET 3212": 16}
OUTPUT_REFERENCES = ("TSX DST 1635", "TSX DST 2472")


def make_types() -> dict[str, type[IntelligentModule]]:
    types: dict[str, type[IntelligentModule]] = {}
    for name, points in INPUT_REFERENCES.items():
        types[name] = type(
            name.replace(" ", ""), (DiscreteInputs,), {"type_name": name, "points": points}
        )
    for name in OUTPUT_REFERENCES:
        types[name] = type(name.replace(" ", ""), (DiscreteOutputs,), {"type_name": name})
    return types
