"""The logbook: the 200-message stack and the time base that stamps what enters it.

The module holds one :class:`Logbook` (composition, not a mixin).  The logbook
stores messages stamped by the module clock (DEM 2.3-4, 4.2-2), takes the
synchronization pulses into the time base and watches for a missing one (4.1-3,
AMB-DEM-16), and times the periodic overall-state message (3.2-1 PER) on the module's
own clock, the only clock the module has: it is due every PER minutes of module time
from the time setting, so its time-stamps fall on whole minutes of module time even
when that clock drifts or runs free in a synchronization fault (2.5-6).  Whether a
message may be logged at all (configuration, global stop, channel selection) is the
module's decision.
"""

from __future__ import annotations

from collections.abc import Callable

from fieldtwin.clock import Handle
from fieldtwin.tsx.dem24.civil import CivilTime
from fieldtwin.tsx.dem24.stack import Body, Message, MessageStack, MessageType
from fieldtwin.tsx.dem24.timebase import SyncOutcome, Timebase, TimeReference, TimeState

MINUTE_MS = 60_000
_new_message = tuple.__new__
from_ms = CivilTime.from_ms

Schedule = Callable[[int, Callable[[int], None]], Handle]
# (message as offered, stored?, flagged as following a loss?, messages in the stack after)
LogTap = Callable[[Message, bool, bool, int], None]


class Logbook:
    """Stack + time base of one module in rack ``rack``, slot ``slot``.

    ``schedule(at, callback)`` is the module's (a power-off cancels it);
    ``periodic(now)`` logs the overall state when PER is due; ``lost(now)`` is told
    when a pulse is missing.
    """

    def __init__(
        self,
        rack: int,
        slot: int,
        drift_ppm: float,
        schedule: Schedule,
        periodic: Callable[[int], None],
        lost: Callable[[int], None],
    ) -> None:
        self.rack = rack
        self.slot = slot
        self.timebase = Timebase(drift_ppm=drift_ppm)
        self.stack = MessageStack()
        self._schedule = schedule
        self._on_periodic = periodic
        self._on_lost = lost
        self._per_ms = 0  # 0: no periodic logging
        self._periodic: Handle | None = None
        self._periodic_due_ms: int | None = None
        self._loss: Handle | None = None
        self.tap: LogTap | None = None  # an observer of every message offered (the event bus)
        # told before the module clock is reset, set again or drifts otherwise (the inputs'
        # stamps not computed yet: InputBank.settle_stamps)
        self.before_change: Callable[[], None] | None = None

    def reset(self, drift_ppm: float) -> None:
        """DEM 2.5-3 power-up: no protected memory, time and messages are lost."""
        self._clock_changes()
        self.timebase = Timebase(drift_ppm=drift_ppm)
        self.stack = MessageStack()
        self._per_ms, self._periodic_due_ms = 0, None
        self._cancel_periodic()
        if self._loss is not None:
            self._loss.cancel()
            self._loss = None

    def configure(self, t_syn_s: int, drift_ms: int, per_min: int) -> None:
        """T-SYN, DRIFT and PER of an accepted configuration (DEM 3.2-1)."""
        self.timebase.t_syn_ms, self.timebase.drift_ms = t_syn_s * 1000, drift_ms
        self._per_ms = per_min * MINUTE_MS

    # --- messages ---------------------------------------------------------------------

    def stamp(self, t: int) -> int | None:
        """Module time in ms at ``t``; None while the time is not set (nothing is logged)."""
        timebase = self.timebase
        state = timebase.machine.state  # timebase.ready, inlined (once per edge)
        if state is TimeState.SET or state is TimeState.SET_RECEIVED:
            return timebase.clock.ms(t)
        return None

    def push(self, message_type: MessageType, stamp: int, body: Body) -> bool:
        """Store a message stamped ``stamp`` ms; True when the stack is now full."""
        tb = self.timebase
        # Message(message_type, CivilTime.from_ms(stamp), ...), made as a tuple in C
        message = _new_message(
            Message,
            (
                message_type,
                from_ms(stamp),
                tb.fault,
                tb.indicator,
                self.rack,
                self.slot,
                body,
                False,
            ),
        )
        stack = self.stack
        tap = self.tap
        if tap is None:
            stack.push(message)  # DEM 2.3-4: lost when full, flagged in the next one
        else:
            flagged = bool(stack.lost) and not stack.full
            tap(message, stack.push(message), flagged, len(stack))
        return stack.full

    def read(self, count: int) -> list[Message]:
        """Remove and return up to ``count`` messages, oldest first (DEM 4.2-3)."""
        return self.stack.pop(count)

    # --- the time base ------------------------------------------------------------------

    def reference(self, ref: TimeReference, now: int) -> SyncOutcome:
        """Request 2: a time waiting for the next pulse (DEM 4.1-2)."""
        return self.timebase.reference(ref, now)

    def pulse(self, edge: int, now: int) -> SyncOutcome:
        """A pulse whose leading edge was at ``edge``: check or set the clock, watch for
        the next one, and find the periodic instant again (the clock may have moved)."""
        self._clock_changes()
        outcome = self.timebase.pulse(edge)
        if self._loss is not None:
            self._loss.cancel()
            self._loss = None
        deadline = self.timebase.loss_deadline()
        if deadline is not None:  # the next pulse is recognised as late as this one was
            self._loss = self._schedule(deadline + (now - edge), self._lost)
        if outcome.time_set:
            self.start_periodic(now)  # PER counted in module time from the time setting
        else:
            self.rearm_periodic(now)
        return outcome

    def _lost(self, now: int) -> None:
        self._loss = None
        self._on_lost(now)

    def _clock_changes(self) -> None:
        if self.before_change is not None:
            self.before_change()

    def set_drift(self, drift_ppm: float, now: int) -> None:
        self._clock_changes()
        self.timebase.clock.set_drift(drift_ppm, now)
        self.rearm_periodic(now)

    # --- periodic logging on the module clock (DEM 3.2-1 PER) ----------------------------

    def start_periodic(self, now: int) -> None:
        """PER minutes of module time from now (the time setting, a new configuration)."""
        self._periodic_due_ms = None
        if self._per_ms and self.timebase.ready:
            self._periodic_due_ms = self.timebase.clock.ms(now) + self._per_ms
        self.rearm_periodic(now)

    def stop_periodic(self) -> None:
        self._periodic_due_ms = None
        self._cancel_periodic()

    def rearm_periodic(self, now: int) -> None:
        """(Re)compute when the module clock reaches the due time: after a pulse resets
        the clock or its drift changes, the same module time falls at another instant."""
        self._cancel_periodic()
        if self._periodic_due_ms is not None:
            at = self.timebase.clock.when(self._periodic_due_ms, now)
            self._periodic = self._schedule(at, self._periodic_log)

    def _cancel_periodic(self) -> None:
        if self._periodic is not None:
            self._periodic.cancel()
            self._periodic = None

    def _periodic_log(self, now: int) -> None:
        self._periodic = None
        self._on_periodic(now)  # DEM 3.2-1 PER: overall state every PER minutes
        if self._periodic_due_ms is not None:
            self._periodic_due_ms += self._per_ms
        self.rearm_periodic(now)
