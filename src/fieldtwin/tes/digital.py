"""Digital inputs (§4.1.1 - 4.1.5): filter, memorized inputs, counters, chronometers.

Event-driven: a direct change schedules its confirmation after the filter time
of the new state; chronometers are computed at read time from the time of the
last filtered change (DESIGN rule 3).
"""

from __future__ import annotations

import enum
from collections.abc import Callable
from dataclasses import dataclass, field

from fieldtwin.clock import MS, Handle, SimClock

TICK = 100 * MS  # §4.1.4 / §6.2.5 chronometers in 1/10 s
FILTER_BASE = 5 * MS  # §4.1.1 steps of 5 ms
MASK32 = 0xFFFFFFFF


class Wiring(enum.Enum):
    """The line between a sensor and a TES 32ET-S input (§4.1.5)."""

    OK = "ok"
    SHORT = "short"  # short circuit: the input reads 1
    OPEN = "open"  # broken wire: the input reads 0


@dataclass(slots=True)
class _Input:
    contact: bool = False  # the sensor's state
    wiring: Wiring = Wiring.OK
    direct: bool = False
    filtered: bool = False
    pending: Handle | None = None
    memorized: bool = False
    changes: int = 0  # §4.1.2 memorized changes not yet restored
    rise: int = 0
    fall: int = 0
    since: int = 0  # time of the last filtered change
    bias: int = 0  # us added to the running state's duration (a master write)
    last: list[int] = field(default_factory=lambda: [0, 0])  # ticks of the last 0 / 1 state
    cumulated: list[int] = field(default_factory=lambda: [0, 0])  # us of closed 0 / 1 states


class DigitalInputs:
    """The ``count`` digital inputs of one TES."""

    def __init__(self, count: int, clock: SimClock, filter_ticks: Callable[[bool], int]) -> None:
        self.count = count
        self._clock = clock
        self._filter_ticks = filter_ticks
        self._inputs = [_Input() for _ in range(count)]
        self.on_change: Callable[[int, bool, int], None] | None = None

    # --- power -------------------------------------------------------------

    def power_on(self, now: int) -> None:
        """RAM is lost: states restart from the present direct inputs."""
        self.power_off()
        for j, old in enumerate(self._inputs):
            inp = _Input(contact=old.contact, wiring=old.wiring, since=now)
            inp.direct = inp.filtered = inp.memorized = self._electrical(inp)
            self._inputs[j] = inp

    def power_off(self) -> None:
        for inp in self._inputs:
            if inp.pending is not None:
                inp.pending.cancel()
                inp.pending = None

    # --- the field side ----------------------------------------------------

    def set_contact(self, i: int, value: bool, now: int) -> None:
        self._inputs[i].contact = value
        self._update(i, now)

    def set_wiring(self, i: int, wiring: Wiring, now: int) -> None:
        self._inputs[i].wiring = wiring
        self._update(i, now)

    def wiring(self, i: int) -> Wiring:
        return self._inputs[i].wiring

    @staticmethod
    def _electrical(inp: _Input) -> bool:
        # AMB-TES-23 reading: a short circuit looks closed, a broken wire open
        if inp.wiring is Wiring.SHORT:
            return True
        if inp.wiring is Wiring.OPEN:
            return False
        return inp.contact

    def _update(self, i: int, now: int) -> None:
        inp = self._inputs[i]
        value = self._electrical(inp)
        if value == inp.direct:
            return
        inp.direct = value
        if inp.pending is not None:
            inp.pending.cancel()
            inp.pending = None
        if value == inp.filtered:
            return  # §4.1.1 the new state was not confirmed: nothing happened
        delay = self._filter_ticks(value) * FILTER_BASE
        if delay == 0:
            self._confirm(i, value, now)
        else:
            inp.pending = self._clock.schedule(now + delay, lambda t: self._confirm(i, value, t))

    def _confirm(self, i: int, value: bool, now: int) -> None:
        """§4.1.1 the state held for the filter time: the filtered input changes."""
        inp = self._inputs[i]
        inp.pending = None
        old = int(inp.filtered)
        inp.last[old] = self._running_ticks(inp, now)  # §4.1.4 duration of last state
        inp.cumulated[old] += now - inp.since
        inp.since, inp.bias = now, 0
        inp.filtered = value
        if value:
            inp.rise = (inp.rise + 1) & MASK32  # §4.1.3
        else:
            inp.fall = (inp.fall + 1) & MASK32
        inp.changes += 1  # §4.1.2
        if self.on_change is not None:
            self.on_change(i, value, now)

    # --- what the map shows ------------------------------------------------

    def bits(self, attr: str, word: int) -> int:
        """A 16-bit word of ``direct``, ``filtered`` or ``memorized`` bits."""
        out = 0
        for bit, inp in enumerate(self._inputs[16 * word : 16 * word + 16]):
            if getattr(inp, attr):
                out |= 1 << bit
        return out

    def restore_memorized(self, word: int) -> None:
        """§4.1.2 a master read: each input of ``word`` with changes toggles once."""
        for inp in self._inputs[16 * word : 16 * word + 16]:
            if inp.changes > 0:
                inp.memorized = not inp.memorized
                inp.changes -= 1

    @property
    def changes_pending(self) -> bool:
        return any(inp.changes for inp in self._inputs)

    def direct(self, i: int) -> bool:
        return self._inputs[i].direct

    def filtered(self, i: int) -> bool:
        return self._inputs[i].filtered

    @staticmethod
    def _running_ticks(inp: _Input, now: int) -> int:
        return (now - inp.since + inp.bias) // TICK

    def value32(self, kind: str, i: int, now: int) -> int:
        """counter_rise/fall, duration_0/1, cumulated_0/1 of input ``i``."""
        inp = self._inputs[i]
        if kind == "counter_rise":
            return inp.rise
        if kind == "counter_fall":
            return inp.fall
        state = int(kind[-1])
        running = inp.filtered == bool(state)
        if kind.startswith("duration"):  # §4.1.4 last state, or the state in progress
            return (self._running_ticks(inp, now) if running else inp.last[state]) & MASK32
        extra = now - inp.since if running else 0
        return ((inp.cumulated[state] + extra) // TICK) & MASK32

    def set_value32(self, kind: str, i: int, value: int, now: int) -> None:
        """A master write (§4.1.3 "Modbus master can reset counters")."""
        inp = self._inputs[i]
        if kind == "counter_rise":
            inp.rise = value
            return
        if kind == "counter_fall":
            inp.fall = value
            return
        state = int(kind[-1])
        running = inp.filtered == bool(state)
        if kind.startswith("duration"):
            if running:
                inp.bias = value * TICK - (now - inp.since)
            else:
                inp.last[state] = value
            return
        extra = now - inp.since if running else 0
        inp.cumulated[state] = value * TICK - extra
