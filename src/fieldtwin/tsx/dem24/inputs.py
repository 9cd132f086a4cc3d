"""The 24 discrete inputs: voltage thresholds, the 500 us hardware filter and FILT (2.1-1).

An input is a bool, or a voltage judged against the IEC 61131-2 type 1 limits of the
24 V (DEM 2412) or 48 V (DEM 2413) module (7.2 "Type 1"); between the limits the
input keeps its state.  A change is accepted once the level has held for the
hardware filter (500 us, 1.2-1) and the software filter FILT (0/10/20/50 ms, 3.2-1),
whichever is longer; the change is time-stamped at its edge, to the millisecond of
the module clock.  Signals say when they next change: the bank schedules exactly
those edges (DESIGN rule 3), and for voltages the instant a type 1 limit is crossed,
between breakpoints too (:mod:`fieldtwin.tsx.dem24.crossing`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

from fieldtwin.clock import MS, Handle, SimClock
from fieldtwin.errors import ConfigError
from fieldtwin.signals import AnalogSignal, DiscreteSignal
from fieldtwin.signals.base import SteppedSignal
from fieldtwin.tsx.dem24.crossing import next_event

CHANNELS = 24
HARDWARE_FILTER_US = 500
UNSTAMPED = -1  # a stamp not computed yet: the module clock's reading at the edge, later
InputSignal = DiscreteSignal | AnalogSignal  # DEM 1.2-1 "500 microsecond filtering"


@dataclass(frozen=True, slots=True)
class Thresholds:
    """IEC 61131-2 type 1: OFF at or below ``off_max``, ON at or above ``on_min`` (volts)."""

    nominal: int
    off_max: float
    on_min: float
    maximum: float

    def judge(self, volts: float, previous: bool) -> bool:
        if volts >= self.on_min:
            return True
        if volts <= self.off_max:
            return False
        return previous  # transition zone: undefined, the input keeps its state


TYPE1_24V = Thresholds(24, 5.0, 15.0, 30.0)
TYPE1_48V = Thresholds(48, 10.0, 34.0, 60.0)


def check_channel(channel: int) -> int:
    if isinstance(channel, bool) or not isinstance(channel, int) or not 0 <= channel < CHANNELS:
        raise ConfigError(f"channel {channel!r} out of range (allowed 0..{CHANNELS - 1})")
    return channel


class _Channel:
    __slots__ = (
        "confirm",
        "edge_t",
        "follow",
        "level",
        "pending",
        "raw",
        "signal",
        "signal_handle",
        "stamp",
        "step",
    )

    def __init__(self, follow: Callback, confirm: Callback) -> None:
        self.follow = follow  # the clock callbacks of this channel, made once
        self.confirm = confirm
        self.raw = False  # at the terminals
        self.level = False  # after the filters
        self.pending: Handle | None = None
        self.edge_t = 0
        self.stamp: int | None = None
        self.signal: InputSignal | None = None
        self.signal_handle: Handle | None = None
        self.step: Callable[[int], tuple[bool, int | None]] | None = None


Callback = Callable[[int], None]
Accept = Callable[[int, bool, int, int | None, int], None]  # channel, level, edge, stamp, now


class InputBank:
    """Raw levels, filters and accepted levels of the 24 channels.

    ``stepped``: a discrete signal that answers its value and next change in one call
    (:class:`~fieldtwin.signals.base.SteppedSignal`) is asked once per edge; False
    (the reference of the tests) asks ``value_at`` and ``next_change`` as before.

    ``folded``: at a stepped signal's edge the filter's confirmation runs inline
    (``SimClock.run_inline``) when nothing else is due before its instant: the same
    callback at the same instant, counted as fired, with the sequence number its
    scheduling would have taken, so every event keeps its order; only the heap entry
    is saved.  False (the reference of the tests): always a clock event.
    """

    stepped = True
    folded = True
    # lazy_stamps: a stepped signal's edge leaves its stamp UNSTAMPED; whoever logs it
    # reads the module clock at the edge then (an oscillating input's is never read), and
    # every stamp left is fixed (settle_stamps) before a pulse or a drift change moves the
    # clock.  False (the reference of the tests): stamped at the edge
    lazy_stamps = True

    def __init__(
        self,
        clock: SimClock,
        thresholds: Thresholds,
        stamp: Callable[[int], int | None],
        accept: Accept,
    ) -> None:
        self.clock = clock
        self._schedule = clock.schedule
        self._reserve = clock.reserve
        self._schedule_as = clock.schedule_as
        self._run_inline = clock.run_inline
        self.thresholds = thresholds
        self._stamp = stamp
        self._accept = accept
        self._ch = [
            _Channel(self._follower(channel), self._confirmer(channel))
            for channel in range(CHANNELS)
        ]
        self.active = False  # module operational and inputs readable
        self.filter_us = HARDWARE_FILTER_US
        self.supply_ok = True  # without field supply every input reads 0
        # the accepted levels, bit i = channel i (IWxy,6/7); read it, never write it
        self.level_bits = 0

    def set_filter_ms(self, filt_ms: int) -> None:
        self.filter_us = max(HARDWARE_FILTER_US, filt_ms * MS)

    def raw(self, channel: int) -> bool:
        return self._ch[channel].raw

    def level(self, channel: int) -> bool:
        return self._ch[channel].level

    def levels(self) -> int:
        return self.level_bits

    # --- the terminals ------------------------------------------------------------

    def set_raw(self, channel: int, value: bool, t: int) -> None:
        ch = self._ch[channel]
        if ch.raw == value:
            return
        ch.raw = value
        self._edge(channel, t)

    def set_value(self, channel: int, value: bool | float, t: int) -> None:
        """A bool, or volts judged against the type 1 limits (7.2)."""
        if isinstance(value, bool):
            self.set_raw(channel, value, t)
            return
        if not isinstance(value, int | float) or value != value or abs(value) == float("inf"):
            raise ConfigError(f"input {channel}: {value!r} is not a bool or a voltage")
        self.set_raw(channel, self.thresholds.judge(float(value), self._ch[channel].raw), t)

    def attach(self, channel: int, signal: InputSignal | None) -> None:
        ch = self._ch[channel]
        if ch.signal_handle is not None:
            ch.signal_handle.cancel()
            ch.signal_handle = None
        ch.signal = signal
        ch.step = (
            signal.value_and_next if self.stepped and isinstance(signal, SteppedSignal) else None
        )
        if signal is not None:
            self._follow(channel, self.clock.now)

    def _follower(self, channel: int) -> Callback:
        return partial(self._follow, channel)  # now -> self._follow(channel, now)

    def _confirmer(self, channel: int) -> Callback:
        return partial(self._confirm, channel)

    def _follow(self, channel: int, t: int) -> None:
        ch = self._ch[channel]
        step = ch.step
        if step is not None:  # set_raw, with the next change found by the same search
            level, nxt = step(t)
            schedule = self._schedule
            if ch.raw != level:
                ch.raw = level
                # self._edge(channel, t), inlined
                pending = ch.pending
                if pending is not None:
                    pending.cancel()  # a pulse shorter than the filter is rejected
                    ch.pending = None
                if self.active and (level and self.supply_ok) != ch.level:
                    # stamped at the edge, now or (lazy_stamps) when logged
                    ch.edge_t, ch.stamp = t, UNSTAMPED if self.lazy_stamps else self._stamp(t)
                    if self.folded:
                        # the confirmation's sequence number, then the next edge's (as
                        # scheduled in this order); inline when nothing comes between
                        seq = self._reserve()
                        ch.signal_handle = None if nxt is None else schedule(nxt, ch.follow)
                        at = t + self.filter_us
                        if not self._run_inline(at, seq, ch.confirm):
                            ch.pending = self._schedule_as(at, seq, ch.confirm)
                        return
                    ch.pending = schedule(t + self.filter_us, ch.confirm)
            ch.signal_handle = None if nxt is None else schedule(nxt, ch.follow)
            return
        assert ch.signal is not None
        value = ch.signal.value_at(t)
        self.set_value(channel, value, t)
        if isinstance(value, bool):
            nxt = ch.signal.next_change(t)
        else:  # volts: judged at the instant they cross a type 1 limit (7.2)
            nxt = next_event(ch.signal, t, ch.raw, self.thresholds)  # type: ignore[arg-type]
        ch.signal_handle = None if nxt is None else self._schedule(nxt, ch.follow)

    # --- the filters ----------------------------------------------------------------

    def _effective(self, ch: _Channel) -> bool:
        return ch.raw and self.supply_ok

    def _edge(self, channel: int, t: int) -> None:
        ch = self._ch[channel]
        pending = ch.pending
        if pending is not None:
            pending.cancel()  # a pulse shorter than the filter is rejected
            ch.pending = None
        # _effective(ch) inlined
        if not self.active or (ch.raw and self.supply_ok) == ch.level:
            return
        ch.edge_t, ch.stamp = t, self._stamp(t)  # stamped at the edge (manual-notes)
        ch.pending = self.clock.schedule(t + self.filter_us, ch.confirm)

    def settle_stamps(self) -> None:
        """Stamp every edge left UNSTAMPED with the module clock as it is: called before
        anything changes what the clock read at a past instant (a pulse, a drift)."""
        stamp = self._stamp
        for ch in self._ch:
            if ch.stamp == UNSTAMPED:
                ch.stamp = stamp(ch.edge_t)

    def _confirm(self, channel: int, now: int) -> None:
        ch = self._ch[channel]
        ch.pending = None
        ch.level = level = ch.raw and self.supply_ok  # _effective(ch)
        bits = self.level_bits
        self.level_bits = bits | (1 << channel) if level else bits & ~(1 << channel)
        self._accept(channel, ch.level, ch.edge_t, ch.stamp, now)

    def supply(self, ok: bool, t: int) -> None:
        """Field supply on/off: every input high at the terminals follows it."""
        self.supply_ok = ok
        for channel, ch in enumerate(self._ch):
            if ch.raw:
                self._edge(channel, t)

    def start(self, now: int, *, silent: bool) -> None:
        """Inputs readable again (self-test done, terminal block back): take the levels."""
        self.active = True
        for channel, ch in enumerate(self._ch):
            value = self._effective(ch)
            if value != ch.level:
                ch.level = value
                self.level_bits ^= 1 << channel
                if not silent:
                    self._accept(channel, value, now, self._stamp(now), now)

    def stop(self) -> None:
        """Inputs unreadable (power off, terminal block out): cancel the filters."""
        self.active = False
        for ch in self._ch:
            if ch.pending is not None:
                ch.pending.cancel()
                ch.pending = None

    def reset_levels(self) -> None:
        for ch in self._ch:
            ch.level = False
        self.level_bits = 0
