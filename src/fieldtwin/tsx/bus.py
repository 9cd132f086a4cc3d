"""Values the TSX bus and its modules exchange: modes, LEDs, bus images, context."""

from __future__ import annotations

import enum
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal, Protocol

from fieldtwin.clock import SimClock


class ModuleState(enum.Enum):
    OFF = "off"  # no power: PLC off, or module out of its slot
    SELF_TEST = "self-test"
    OPERATIONAL = "operational"  # Run or Stop, see IWxy,0,C
    BLOCKED = "blocked"  # blocking fault: out of service until power-up


class ModuleEvent(enum.Enum):
    POWER_ON = "power on"
    SELF_TEST_DONE = "self-test done"
    BLOCKING_FAULT = "blocking fault"
    POWER_OFF = "power off"


# A front-panel LED: lit, dark or blinking
LedState = Literal["on", "off", "blink"]


@dataclass(frozen=True, slots=True)
class BusImage:
    """What the PLC reads from a slot at a bus refresh."""

    iw: tuple[int, ...]
    i_bits: int
    fault: bool  # Ixy,S


class Pacer(Protocol):
    """What paces simulated time to the wall clock (fieldtwin.runtime.runner.Runner)."""

    def advance(self, duration: int) -> None: ...

    def run_until(self, predicate: Callable[[], bool], limit: int) -> bool: ...


@dataclass(frozen=True, slots=True)
class ModuleContext:
    """What the PLC gives a module it inserts."""

    clock: SimClock
    plc_model: str = "TSX 87"
    # Returns the PLC's fieldtwin.runtime.runner.Runner, creating it: call it when the
    # module wires a real endpoint (pty, serial, TCP), so that simulated time follows
    # the wall clock, also inside plc.advance and plc.exchange (SCM issue).
    pace: Callable[[], Pacer] | None = None
