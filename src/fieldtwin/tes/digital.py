"""Digital inputs (§4.1.1 - 4.1.5): filter, memorized inputs, counters, chronometers.

Event-driven: a direct change schedules its confirmation after the filter time
of the new state; chronometers are computed at read time from the time of the
last filtered change (DESIGN rule 3).

An input driven by a signal (``follow``) is computed at read time (issue 15): its
edges and their confirmations are not clock events; every reading or writing method
here first catches the followed inputs up to the present, edge by edge, in the order
the clock would have run them (a confirmation before an edge of the same instant),
and a pulse train in its steady regime jumps whole periods at once.  The TES calls
``sync`` before a master write of a parameter (the filter times) as well.  A
per-clock :class:`Beat` keeps the clock busy while inputs are followed (one event
per simulated second: a plant of pulsing TES still runs at ``--speed max``) and
catches each followed input up at least once a minute of simulated time.
``DigitalInputs.lazy = False`` restores an event per edge (the property test's
reference, tests/tes/test_tes_lazy_inputs.py).
"""

from __future__ import annotations

import enum
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from itertools import compress
from operator import attrgetter
from typing import Protocol

from fieldtwin.clock import MS, Handle, S, SimClock
from fieldtwin.signals.base import SteppedSignal
from fieldtwin.signals.discrete import PulseTrain

TICK = 100 * MS  # §4.1.4 / §6.2.5 chronometers in 1/10 s
# an input's states, for making its bit masks again (one C call per input)
_DIRECT, _FILTERED = attrgetter("direct"), attrgetter("filtered")
_MEMORIZED, _CHANGES = attrgetter("memorized"), attrgetter("changes")
_BIT32 = tuple(1 << i for i in range(32))  # the bit of each input in its mask
MEMORIZED, FILTERED, DIRECT = 0, 1, 2  # the states of a read plan's bit words
FILTER_BASE = 5 * MS  # §4.1.1 steps of 5 ms
MASK32 = 0xFFFFFFFF


class Wiring(enum.Enum):
    """The line between a sensor and a TES 32ET-S input (§4.1.5)."""

    OK = "ok"
    SHORT = "short"  # short circuit: the input reads 1
    OPEN = "open"  # broken wire: the input reads 0


class DiscreteSource(Protocol):
    """Anything with the fieldtwin.signals DiscreteSignal methods."""

    def value_at(self, t_us: int) -> bool: ...

    def next_change(self, t_us: int) -> int | None: ...


Step = Callable[[int], tuple[bool, int | None]]
# a bit word of a read plan: (MEMORIZED, FILTERED or DIRECT, first input), or None
BitWord = tuple[int, int] | None
# a word of a 32-bit value of a read plan: (kind's name, input, low half), or None
PairWord = tuple[str, int, bool] | None  # t -> (value at t, next change after t)


@dataclass(slots=True)
class _Follow:
    """A signal an input follows at read time: the time of its next edge."""

    step: Step  # the signal's value and next change, one search where it can
    next_edge: int | None
    pulse: PulseTrain | None  # a pulse train: whole periods can be jumped


def _stepper(signal: DiscreteSource) -> Step:
    if isinstance(signal, SteppedSignal):
        return signal.value_and_next
    return lambda t: (signal.value_at(t), signal.next_change(t))


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
    follow: _Follow | None = None  # followed at read time (lazy)
    pending_at: int | None = None  # a followed input's confirmation: when,
    pending_value: bool = False  # to which state,
    pending_edge: int = 0  # and the edge it confirms


class DigitalInputs:
    """The ``count`` digital inputs of one TES."""

    lazy = True  # followed inputs computed at read time (False: an event per edge)

    def __init__(self, count: int, clock: SimClock, filter_ticks: Callable[[bool], int]) -> None:
        self.count = count
        self._clock = clock
        self._filter_ticks = filter_ticks
        self._inputs = [_Input() for _ in range(count)]
        self.on_change: Callable[[int, bool, int], None] | None = None
        self._followed: list[int] = []  # inputs that follow a signal at read time
        self._synced = -1  # the instant the followed inputs were caught up to
        self._drivers: dict[int, Handle] = {}  # lazy = False: each input's next edge
        # the inputs' states as bit masks (bit i: input i), kept with the inputs: a word of
        # the map is a shift (``bits``); ``changed``: inputs whose memorized changes wait
        self.direct_bits = 0
        self.filtered_bits = 0
        self.memorized_bits = 0
        self.changed_bits = 0

    # --- power -------------------------------------------------------------

    def power_on(self, now: int) -> None:
        """RAM is lost: states restart from the present direct inputs."""
        self.power_off()
        for j, old in enumerate(self._inputs):
            inp = _Input(contact=old.contact, wiring=old.wiring, since=now, follow=old.follow)
            inp.direct = inp.filtered = inp.memorized = self._electrical(inp)
            self._inputs[j] = inp
        self._remask()

    def _remask(self) -> None:
        """The bit masks made again from the inputs."""
        masks = self._masks_of_inputs()
        self.direct_bits, self.filtered_bits, self.memorized_bits, self.changed_bits = masks

    def _masks_of_inputs(self) -> tuple[int, int, int, int]:
        inputs = self._inputs
        return (
            sum(compress(_BIT32, map(_DIRECT, inputs))),
            sum(compress(_BIT32, map(_FILTERED, inputs))),
            sum(compress(_BIT32, map(_MEMORIZED, inputs))),
            sum(compress(_BIT32, map(_CHANGES, inputs))),
        )

    def masks_agree(self) -> bool:
        """The bit masks are what the inputs hold (the tests' check; no side effect)."""
        masks = (self.direct_bits, self.filtered_bits, self.memorized_bits, self.changed_bits)
        return masks == self._masks_of_inputs()

    def power_off(self) -> None:
        self.sync()
        for inp in self._inputs:
            if inp.pending is not None:
                inp.pending.cancel()
                inp.pending = None
            inp.pending_at = None

    # --- the field side ----------------------------------------------------

    def set_contact(self, i: int, value: bool, now: int) -> None:
        self.sync()
        self._inputs[i].contact = value
        self._update(i, now)

    def set_wiring(self, i: int, wiring: Wiring, now: int) -> None:
        self.sync()
        self._inputs[i].wiring = wiring
        self._update(i, now)

    def follow(self, i: int, signal: DiscreteSource, now: int) -> None:
        """Input ``i`` follows ``signal`` from ``now`` on (its value now, then its edges)."""
        self.unfollow(i)
        if not self.lazy or self.on_change is not None:
            self._step(i, signal, now)  # an event per edge
            return
        self.sync()
        inp = self._inputs[i]
        step = _stepper(signal)
        value, at = step(now)
        pulse = signal if isinstance(signal, PulseTrain) else None
        inp.follow = _Follow(step, None if at is None else max(at, now + 1), pulse)
        self._followed.append(i)
        if inp.pending is not None:  # confirmed at read time from now on
            at = inp.pending.time
            inp.pending.cancel()
            inp.pending = None
            inp.pending_at, inp.pending_value = at, inp.direct
            inp.pending_edge = at - self._delay(inp.direct)
        inp.contact = bool(value)
        self._update(i, now)
        Beat.of(self._clock).join(self)

    def unfollow(self, i: int) -> None:
        """Input ``i`` follows no signal any more (caught up to now first)."""
        handle = self._drivers.pop(i, None)
        if handle is not None:
            handle.cancel()
        inp = self._inputs[i]
        if inp.follow is None:
            return
        self.sync()
        self._release(i, inp)

    def _release(self, i: int, inp: _Input) -> None:
        inp.follow = None
        self._followed.remove(i)
        if inp.pending_at is not None:  # its confirmation becomes a clock event again
            at, value = inp.pending_at, inp.pending_value
            inp.pending_at = None
            inp.pending = self._clock.schedule(at, lambda t: self._confirm(i, value, t))
        if not self._followed:
            Beat.of(self._clock).leave(self)

    def _step(self, i: int, signal: DiscreteSource, now: int) -> None:
        """lazy = False: apply the signal now and schedule its next edge."""
        self._drivers.pop(i, None)
        self.set_contact(i, bool(signal.value_at(now)), now)
        at = signal.next_change(now)
        if at is not None:
            self._drivers[i] = self._clock.schedule(
                max(at, now + 1), lambda t: self._step(i, signal, t)
            )

    # --- read time -----------------------------------------------------------

    @property
    def followed(self) -> int:
        """How many inputs follow a signal at read time."""
        return len(self._followed)

    def sync(self) -> None:
        """Catch the followed inputs up to the present (their edges and confirmations)."""
        now = self._clock.now
        if self._synced == now or not self._followed:
            return
        self._synced = now
        for i in tuple(self._followed):
            self._catch_up(i, self._inputs[i], now)

    def _delay(self, value: bool) -> int:
        return self._filter_ticks(value) * FILTER_BASE

    def _catch_up(self, i: int, inp: _Input, now: int) -> None:
        """The edges and confirmations of input ``i`` up to ``now``, in clock order."""
        fol = inp.follow
        assert fol is not None
        step = fol.step
        while True:
            p, e = inp.pending_at, fol.next_edge
            if p is not None and p <= now and (e is None or p <= e):
                # scheduled at the edge, before the next edge: first at the same instant
                inp.pending_at = None
                value = inp.pending_value
                self._confirm(i, value, p)
                if value and fol.pulse is not None:
                    self._jump(i, inp, fol, fol.pulse, inp.pending_edge, p, now)
                continue
            if e is None or e > now:
                break
            value, at = step(e)
            fol.next_edge = None if at is None else max(at, e + 1)
            inp.contact = bool(value)
            self._update(i, e)
            if inp.filtered and inp.since == e and fol.pulse is not None:  # no filter
                self._jump(i, inp, fol, fol.pulse, e, e, now)
        if fol.next_edge is None and inp.pending_at is None:
            self._release(i, inp)  # nothing will change any more

    def _jump(
        self,
        i: int,
        inp: _Input,
        fol: _Follow,
        pulse: PulseTrain,
        rise: int,
        confirmed: int,
        now: int,
    ) -> None:
        """Just after the rise at ``rise`` was confirmed: skip the whole periods before now.

        In the steady regime (each state at least as long as its filter time), every
        period adds one rise, one fall, two changes and the same two state durations
        to an input: exactly what the edges one by one would leave.
        """
        period, high = pulse.period_us, pulse.high_us
        low = period - high
        if not 0 < high < period or inp.wiring is not Wiring.OK or fol.next_edge != rise + high:
            return
        f1, f0 = self._delay(True), self._delay(False)
        if f1 > high or f0 > low or confirmed != rise + f1:
            return
        k = (now - confirmed) // period - 1
        if k < 1:
            return
        on, off = high + f0 - f1, low - f0 + f1  # the filtered states' durations
        inp.rise = (inp.rise + k) & MASK32
        inp.fall = (inp.fall + k) & MASK32
        inp.changes += 2 * k
        self.changed_bits |= 1 << i
        inp.cumulated[1] += k * on
        inp.cumulated[0] += k * off
        inp.last[1], inp.last[0] = on // TICK, off // TICK
        inp.since = confirmed + k * period
        fol.next_edge = rise + k * period + high

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
        self.direct_bits = self.direct_bits | 1 << i if value else self.direct_bits & ~(1 << i)
        if inp.pending is not None:
            inp.pending.cancel()
            inp.pending = None
        inp.pending_at = None
        if value == inp.filtered:
            return  # §4.1.1 the new state was not confirmed: nothing happened
        delay = self._delay(value)
        if delay == 0:
            self._confirm(i, value, now)
        elif inp.follow is not None:  # confirmed at read time
            inp.pending_at, inp.pending_value, inp.pending_edge = now + delay, value, now
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
        bit = 1 << i
        self.filtered_bits = self.filtered_bits | bit if value else self.filtered_bits & ~bit
        if value:
            inp.rise = (inp.rise + 1) & MASK32  # §4.1.3
        else:
            inp.fall = (inp.fall + 1) & MASK32
        inp.changes += 1  # §4.1.2
        self.changed_bits |= bit
        if self.on_change is not None:
            self.on_change(i, value, now)

    # --- what the map shows ------------------------------------------------

    def bits(self, attr: str, word: int) -> int:
        """A 16-bit word of ``direct``, ``filtered`` or ``memorized`` bits."""
        if self._followed:
            self.sync()
        if attr == "filtered":
            return (self.filtered_bits >> 16 * word) & 0xFFFF
        if attr == "direct":
            return (self.direct_bits >> 16 * word) & 0xFFFF
        if attr == "memorized":
            return (self.memorized_bits >> 16 * word) & 0xFFFF
        states = map(attrgetter(attr), self._inputs[16 * word : 16 * word + 16])
        return sum(compress(_BIT32, states))

    def restore_memorized(self, word: int) -> None:
        """§4.1.2 a master read: each input of ``word`` with changes toggles once."""
        if self._followed:
            self.sync()
        if (self.changed_bits >> 16 * word) & 0xFFFF:  # else nothing changed since
            self._restore(16 * word)

    def _restore(self, first: int) -> None:
        """Each of inputs ``first``..``first + 15`` with changes toggles once."""
        pending = (self.changed_bits >> first) & 0xFFFF
        inputs = self._inputs
        toggled = emptied = 0
        while pending:
            low = pending & -pending  # the lowest input with changes
            pending ^= low
            inp = inputs[first + low.bit_length() - 1]
            inp.memorized = not inp.memorized
            inp.changes -= 1
            toggled |= low
            if not inp.changes:
                emptied |= low
        self.memorized_bits ^= toggled << first
        self.changed_bits &= ~(emptied << first)

    def image(self, spec: tuple[BitWord, ...], now: int = 0) -> tuple[int, ...]:
        """Several bit words in one call, in order (a read plan's run of words 001h..006h):
        each ``(state, first input)`` is what ``bits`` gives for the word of inputs
        ``first``..``first + 15`` of ``MEMORIZED``, ``FILTERED`` or ``DIRECT``, a memorized
        word restored first as ``restore_memorized`` does (AMB-TES-12); ``None`` a word
        of inputs the model lacks (0)."""
        if self._followed:
            self.sync()
        out: list[int] = []
        for word in spec:
            if word is None:
                out.append(0)
            elif word[0] == MEMORIZED:
                first = word[1]
                if (self.changed_bits >> first) & 0xFFFF:
                    self._restore(first)
                out.append((self.memorized_bits >> first) & 0xFFFF)
            elif word[0] == FILTERED:
                out.append((self.filtered_bits >> word[1]) & 0xFFFF)
            else:
                out.append((self.direct_bits >> word[1]) & 0xFFFF)
        return tuple(out)

    @property
    def changes_pending(self) -> bool:
        if self._followed:
            self.sync()
        return self.changed_bits != 0

    def direct(self, i: int) -> bool:
        if self._followed:
            self.sync()
        return self._inputs[i].direct

    def filtered(self, i: int) -> bool:
        if self._followed:
            self.sync()
        return self._inputs[i].filtered

    @staticmethod
    def _running_ticks(inp: _Input, now: int) -> int:
        return (now - inp.since + inp.bias) // TICK

    def value32(self, kind: str, i: int, now: int) -> int:
        """counter_rise/fall, duration_0/1, cumulated_0/1 of input ``i``."""
        if self._followed:
            self.sync()
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

    def pair_words(self, spec: tuple[PairWord, ...], now: int) -> tuple[int, ...]:
        """Several words of 32-bit values in one call, in order (a read plan's run of
        pair words): each ``(kind, input, low)`` the low or high half of ``value32``,
        computed once for the two halves of one value; ``None`` a word of an input the
        model lacks (0, AMB-TES-13)."""
        if self._followed:
            self.sync()
        inputs = self._inputs
        out: list[int] = []
        last: tuple[str, int] | None = None
        value = 0
        for word in spec:
            if word is None:
                out.append(0)
                continue
            kind, i, low = word
            if last != (kind, i):
                last = (kind, i)
                inp = inputs[i]
                if kind == "counter_rise":
                    value = inp.rise
                elif kind == "counter_fall":
                    value = inp.fall
                else:
                    value = self.value32(kind, i, now)
            out.append(value & 0xFFFF if low else (value >> 16) & 0xFFFF)
        return tuple(out)

    def set_pair_words(
        self, spec: tuple[PairWord, ...], values: Sequence[int], k: int, now: int
    ) -> None:
        """Master writes of whole 32-bit values in one call (a write plan's run): each
        ``(kind, input, _)`` set to ``values[k]`` (high) and ``values[k + 1]`` (low) as
        ``set_value32`` does, each next one from the next two values; ``None`` an input
        the model lacks (its two values ignored)."""
        if self._followed:
            self.sync()
        inputs = self._inputs
        for word in spec:
            if word is not None:
                kind, i, _ = word
                value = ((values[k] & 0xFFFF) << 16) | (values[k + 1] & 0xFFFF)
                if kind == "counter_rise":
                    inputs[i].rise = value
                elif kind == "counter_fall":
                    inputs[i].fall = value
                else:
                    self.set_value32(kind, i, value, now)
            k += 2

    def set_value32(self, kind: str, i: int, value: int, now: int) -> None:
        """A master write (§4.1.3 "Modbus master can reset counters")."""
        if self._followed:
            self.sync()
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


BEAT_US = S  # the beat's period: one clock event per simulated second
CATCH_UP_US = 60 * S  # each followed input caught up at least this often


class Beat:
    """One per clock: an event every simulated second while inputs are followed.

    It keeps the clock busy (a plant whose only activity is followed inputs runs at
    ``--speed max`` as it did with an event per edge, and stops as before) and
    catches the followed inputs of a slice of the TES up at each beat, so that each
    is caught up at least once every CATCH_UP_US (a master read after a long quiet
    spell never has hours of edges to go through).
    """

    def __init__(self, clock: SimClock) -> None:
        self._clock = clock
        self._members: deque[DigitalInputs] = deque()
        self._handle: Handle | None = None

    @classmethod
    def of(cls, clock: SimClock) -> Beat:
        beat = clock.shared.get("tes.beat")
        if beat is None:
            beat = clock.shared["tes.beat"] = cls(clock)
        assert isinstance(beat, Beat)
        return beat

    @property
    def members(self) -> int:
        return len(self._members)

    def join(self, inputs: DigitalInputs) -> None:
        if inputs not in self._members:
            self._members.append(inputs)
        if self._handle is None:
            self._handle = self._clock.schedule(self._clock.now + BEAT_US, self._beat)

    def leave(self, inputs: DigitalInputs) -> None:
        if inputs in self._members:
            self._members.remove(inputs)
        if not self._members and self._handle is not None:
            self._handle.cancel()
            self._handle = None

    def _beat(self, now: int) -> None:
        members = self._members
        share = -(-len(members) * BEAT_US // CATCH_UP_US)  # ceil: all within CATCH_UP_US
        for _ in range(share):
            if not members:
                break
            inputs = members[0]
            members.rotate(-1)
            inputs.sync()  # may leave (nothing followed any more)
        self._handle = self._clock.schedule(now + BEAT_US, self._beat) if members else None
