"""The module clock and its time reference (DEM 2.1-2, 2.3-1, 4.1).

The clock counts milliseconds (module time, ms since 1970) with a precision of
25 ppm (7.2); tests give it any drift.  A time reference (request 2) is taken at a
synchronization pulse: the first pulse after reception, or the second after a
power-up (2.3-1, AMB-DEM-09).  The time adopted is the received time rounded up to
the next multiple of T-SYN, plus T-SYN for each further pulse since reception (4.1-3
example: 18:05:33 with 30 s pulses gives 18:06:00; AMB-DEM-08).  At each pulse
the clock is compared with the system time (previous pulse + T-SYN) and reset to it;
a difference above DRIFT, or a pulse missing after T-SYN + DRIFT, is a
synchronization fault (AMB-DEM-16).  In fault the clock runs free (2.5-6); the fault
disappears two pulses after a new time is received (4.1-3).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

from fieldtwin.clock import MS
from fieldtwin.fsm import Machine, Table
from fieldtwin.tsx.dem24.civil import CivilTime, full_year, valid_fields
from fieldtwin.words import bytes_to_words

TIME_BYTES = 8  # DEM 4.1-2: TXTi,L = 8
PRECISION_PPM = 25.0  # DEM 2.1-2, 7.2


@dataclass(frozen=True, slots=True)
class TimeReference:
    """The 4-word table of DEM 4.1-1 (binary bytes, AMB-DEM-07)."""

    time: CivilTime
    indicator: int  # modification indicator 0..255

    @staticmethod
    def decode(data: bytes) -> TimeReference | None:
        """None when the table is refused (length, or a field out of range)."""
        if len(data) != TIME_BYTES:
            return None
        w = bytes_to_words(data)
        yy, month, day, hour = w[0] >> 8, w[0] & 0xFF, w[1] >> 8, w[1] & 0xFF
        minute, second = w[2] >> 8, w[2] & 0xFF
        if not valid_fields(yy, month, day, hour, minute, second):
            return None
        return TimeReference(
            CivilTime(full_year(yy), month, day, hour, minute, second), w[3] & 0xFF
        )

    def encode(self) -> list[int]:
        t = self.time
        return [
            (t.yy << 8) | t.month,
            (t.day << 8) | t.hour,
            (t.minute << 8) | t.second,
            self.indicator & 0xFF,
        ]


class ModuleClock:
    """Module time in us, drifting by ``drift_ppm`` against simulated time."""

    def __init__(self, drift_ppm: float = 0.0) -> None:
        self._base_t = 0
        self._base_mod = 0
        self._ppb = round(drift_ppm * 1000)

    @property
    def drift_ppm(self) -> float:
        return self._ppb / 1000

    def module_us(self, t: int) -> int:
        return self._base_mod + (t - self._base_t) * (1_000_000_000 + self._ppb) // 1_000_000_000

    def ms(self, t: int) -> int:
        """Module time at simulated time ``t``, to the millisecond (DEM 2.1-2)."""
        # module_us(t) // 1000, inlined (once per edge)
        rate = 1_000_000_000 + self._ppb
        return (self._base_mod + (t - self._base_t) * rate // 1_000_000_000) // 1000

    def when(self, value_ms: int, now: int) -> int:
        """The first simulated time >= ``now`` at which the clock reads ``value_ms``."""
        rate = 1_000_000_000 + self._ppb
        t = self._base_t + -(-(value_ms * 1000 - self._base_mod) * 1_000_000_000 // rate)
        t = max(now, t)
        while t > now and self.ms(t - 1) >= value_ms:  # integer rounding: the earliest
            t -= 1
        while self.ms(t) < value_ms:
            t += 1
        return t

    def set_ms(self, t: int, value_ms: int) -> None:
        self._base_t, self._base_mod = t, value_ms * 1000

    def set_drift(self, drift_ppm: float, t: int) -> None:
        self._base_mod, self._base_t = self.module_us(t), t
        self._ppb = round(drift_ppm * 1000)


class TimeState(enum.Enum):
    NOT_SET = "time not set"
    RECEIVED = "time received, waiting for a pulse"
    SET = "time set"
    SET_RECEIVED = "time set, new time waiting for a pulse"


class SyncEvent(enum.Enum):
    REFERENCE = "time reference"
    FIRST_PULSE = "first pulse since power-up"
    PULSE = "pulse"
    PULSE_LOST = "pulse lost"


@dataclass(frozen=True, slots=True)
class SyncOutcome:
    time_set: bool = False  # a reference was adopted
    fault: bool | None = None  # the synchronization fault appeared / disappeared


NOTHING = SyncOutcome()


class Timebase:
    """The time-reference machine (DESIGN rule 4: :data:`TIMEBASE`, one table)."""

    def __init__(self, t_syn_s: int = 60, drift_ms: int = 2, drift_ppm: float = 0.0) -> None:
        self.clock = ModuleClock(drift_ppm)
        self.machine: Machine[TimeState, SyncEvent, Timebase] = Machine(
            TIMEBASE, TimeState.NOT_SET, self
        )
        self.t_syn_ms = t_syn_s * 1000
        self.drift_ms = drift_ms
        self.indicator = 0
        self.fault = False
        self.pulses = 0  # since power-up
        self.pending: TimeReference | None = None
        self._pending_pulses = 0
        self._arm_clear = False
        self.last_ref_ms = 0  # system time at the last pulse
        self.last_pulse_us: int | None = None
        self._outcome = NOTHING  # what the last action found

    @property
    def state(self) -> TimeState:
        return self.machine.state

    # --- inputs -----------------------------------------------------------------

    def reference(self, ref: TimeReference, t: int) -> SyncOutcome:
        self.pending, self._pending_pulses = ref, 0
        return self._fire(SyncEvent.REFERENCE, t)

    def pulse(self, t: int) -> SyncOutcome:
        event = SyncEvent.PULSE if self.pulses else SyncEvent.FIRST_PULSE
        self.pulses += 1
        self._pending_pulses += 1
        outcome = self._fire(event, t)
        self.last_pulse_us = t
        return outcome

    def pulse_lost(self, t: int) -> SyncOutcome:
        return self._fire(SyncEvent.PULSE_LOST, t)

    def loss_deadline(self) -> int | None:
        """When a missing pulse becomes a fault: last pulse + T-SYN + DRIFT (AMB-DEM-16)."""
        if not self.ready or self.last_pulse_us is None:
            return None
        return self.last_pulse_us + self.t_syn_ms * MS + self.drift_ms * MS

    @property
    def ready(self) -> bool:
        """Date set and pulse received (DEM 2.4-2 note (1)): Ixy,0 / IWxy,2,7."""
        state = self.machine.state  # compared by identity: no enum hashing per edge
        return state is TimeState.SET or state is TimeState.SET_RECEIVED

    def now(self, t: int) -> CivilTime:
        return CivilTime.from_ms(self.clock.ms(t))

    # --- the actions of the table ------------------------------------------------------

    def _fire(self, event: SyncEvent, t: int) -> SyncOutcome:
        self._outcome = NOTHING
        self.machine.fire(event, t)
        return self._outcome

    def _candidate(self) -> int:
        assert self.pending is not None
        step = self.t_syn_ms
        received = self.pending.time.to_ms()
        return -(-received // step) * step + (self._pending_pulses - 1) * step

    def _adopt(self, t: int) -> None:
        assert self.pending is not None
        value = self._candidate()
        self.clock.set_ms(t, value)
        self.last_ref_ms, self.indicator = value, self.pending.indicator
        self.pending = None
        self._arm_clear = self.fault  # 4.1-3: fault gone two pulses after the time
        self._outcome = SyncOutcome(time_set=True)

    def _adopt_checked(self, t: int) -> None:
        assert self.pending is not None
        if self.fault or self.pending.indicator != self.indicator:
            self._adopt(t)  # 4.1-3: a new indicator skips the check
            return
        candidate = self._candidate()
        if abs(self.clock.ms(t) - candidate) > self.drift_ms:
            self.pending, self.last_ref_ms = None, candidate
            self._raise(t)
            return
        self._adopt(t)

    def _check(self, t: int) -> None:
        local = self.clock.ms(t)
        step = self.t_syn_ms
        k = max(1, round((local - self.last_ref_ms) / step))
        expected = self.last_ref_ms + k * step
        self.last_ref_ms = expected
        if abs(local - expected) > self.drift_ms:  # 4.1-3 drift above DRIFT
            self._raise(t)
            return
        if self.fault and self._arm_clear:
            self.fault = self._arm_clear = False
            self._outcome = SyncOutcome(fault=False)
        if not self.fault:
            self.clock.set_ms(t, expected)  # 7.2: the pulse resets the card clock

    def _raise(self, t: int) -> None:
        self._arm_clear = False
        if not self.fault:
            self.fault = True
            self._outcome = SyncOutcome(fault=True)


_NS, _RX, _SET, _SRX = (
    TimeState.NOT_SET,
    TimeState.RECEIVED,
    TimeState.SET,
    TimeState.SET_RECEIVED,
)
_REF, _FIRST, _PULSE, _LOST = (
    SyncEvent.REFERENCE,
    SyncEvent.FIRST_PULSE,
    SyncEvent.PULSE,
    SyncEvent.PULSE_LOST,
)

TIMEBASE: Table[TimeState, SyncEvent] = Table(
    "DEM time base",
    TimeState,
    SyncEvent,
    {
        (_NS, _REF): (None, _RX),
        (_NS, _FIRST): (None, _NS),
        (_NS, _PULSE): (None, _NS),
        (_RX, _REF): (None, _RX),
        # 2.3-1: after a power-up the first pulse only starts the period, a second is needed
        (_RX, _FIRST): (None, _RX),
        (_RX, _PULSE): (Timebase._adopt, _SET),
        (_SET, _REF): (None, _SRX),
        (_SET, _PULSE): (Timebase._check, _SET),
        (_SET, _LOST): (Timebase._raise, _SET),
        (_SRX, _REF): (None, _SRX),
        (_SRX, _PULSE): (Timebase._adopt_checked, _SET),
        (_SRX, _LOST): (Timebase._raise, _SRX),
    },
)
