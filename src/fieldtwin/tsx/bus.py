"""Values the TSX bus and its modules exchange: modes, LEDs, bus images, context."""

from __future__ import annotations

import enum
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal, Protocol, runtime_checkable

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
    """What paces simulated time to the wall clock (a host's, e.g. a Runner)."""

    def advance(self, duration: int) -> None: ...

    def run_until(self, predicate: Callable[[], bool], limit: int) -> bool: ...


@runtime_checkable
class Host(Protocol):
    """What a PLC asks of the world outside the cores when a module wires a real endpoint
    (fieldtwin.hosting; the library's is fieldtwin.facade.host)."""

    def pacer(self, clock: SimClock, speed: float | None) -> Pacer: ...

    def open_line(self, url: str, line: Any, pacer: Pacer) -> Any: ...


@dataclass(frozen=True, slots=True)
class ModuleContext:
    """What the PLC gives a module it inserts."""

    clock: SimClock
    plc_model: str = "TSX 87"
    # Returns the PLC's pacer (its host's, e.g. a fieldtwin.runtime.runner.Runner),
    # creating it: call it when the module wires a real endpoint (pty, serial, TCP), so
    # that simulated time follows the wall clock, also inside plc.advance and
    # plc.exchange (SCM issue).
    pace: Callable[[], Pacer] | None = None
    # Opens a real endpoint (URL) for a module's line through the PLC's host, paced.
    open_line: Callable[[str, Any], Any] | None = None
