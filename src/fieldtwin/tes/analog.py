"""Analog inputs (§4.2) and outputs (§4.3) of the TES 4EA, 4SA, 8EA, 8ESA, 8SA-U.

Acquisition runs one channel every 8 ms in turn (§4.2.1).  A channel whose
input is constant and whose average is full of that value stops sampling
until its input changes (DESIGN rule 3): idle analog TES cost nothing.

A channel whose samples can change nothing but its own value (its thresholds out of
the reach of its values, no alarm bit set anywhere, its reflex outputs evaluated) is
sampled lazily (``AnalogInputs.lazy``): no clock event per sample; its value is
caught up, sample by sample at the same instants, when it is read, before anything
that may change its judgement, and once a simulated second (the TES inputs' beat).
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Protocol

from fieldtwin.clock import MS, Handle, SimClock
from fieldtwin.signals import Constant
from fieldtwin.tes.digital import Beat
from fieldtwin.tes.memmap import HISTORY_LENGTH
from fieldtwin.tes.models import TesModel
from fieldtwin.tes.params import DAC_MAX, POINTS_MAX, Value
from fieldtwin.words import to_signed

SLOT = 8 * MS  # §4.2.1 "TES acquire a new analog input every 8ms"


class AnalogSource(Protocol):
    """Anything with the fieldtwin.signals AnalogSignal methods."""

    def value_at(self, t_us: int) -> float: ...

    def next_change(self, t_us: int) -> int | None: ...


def round_half_up(x: float) -> int:
    return math.floor(x + 0.5)


@dataclass(slots=True)
class _Channel:
    number: int
    slot: int
    level: float = 0.0  # electrical value when no signal is attached
    signal: AnalogSource | None = None
    samples: deque[float] = field(default_factory=deque)
    handle: Handle | None = None
    sampled: int = 0  # filtered and scaled (signed): ``value`` once caught up
    acquired: bool = False
    low: bool = False
    high: bool = False
    hysteresis: bool = False  # §4.2.6.2 reflex output state
    history: deque[int] = field(default_factory=lambda: deque(maxlen=HISTORY_LENGTH))
    bit: int = 0  # 1 << number, for the alarm masks
    reflexed: bool = False  # its judgement since acquired went through an evaluation
    behind: int = -1  # sampled lazily: the instant of its last sample taken (else -1)
    owner: AnalogInputs | None = None  # who catches a lazy channel up

    @property
    def value(self) -> int:
        """The filtered, scaled value (signed), caught up to the present."""
        if self.behind >= 0 and self.owner is not None:
            self.owner.catch_up(self, self.owner.now, True)
        return self.sampled


@dataclass(frozen=True, slots=True)
class _Keys:
    """The EEPROM parameter names one channel's acquisition reads (built once)."""

    filter: str
    corr_zero: str
    corr_full: str
    scale: str
    scale_min: str
    scale_max: str

    @classmethod
    def of(cls, k: int) -> _Keys:
        p = f"ai{k}."
        names = ("filter", "corr_zero", "corr_full", "scale", "scale_min", "scale_max")
        return cls(*(p + name for name in names))


class AnalogInputs:
    """The analog input channels of one TES."""

    def __init__(
        self,
        model: TesModel,
        clock: SimClock,
        params: Callable[[], Mapping[str, Value]],
        word: Callable[[int], int],
        on_evaluate: Callable[[int], None],
        on_latch: Callable[[], None] | None = None,
    ) -> None:
        self._model = model
        self._clock = clock
        self._params = params  # the EEPROM values (filter N, scaling, corrections)
        self._word = word  # an MP register (thresholds, outputs, storage period)
        self._on_evaluate = on_evaluate
        # after a sample that changed no threshold state: only the alarm latches
        self._on_latch = on_latch
        self.channels = {
            k: _Channel(k, slot, bit=1 << k, owner=self)
            for slot, k in enumerate(model.analog_inputs)
        }
        self._keys = {k: _Keys.of(k) for k in model.analog_inputs}
        self._period = model.analog_slots * SLOT
        self._full = model.analog_range.full_scale
        # bit k: channel k under its low / over its high threshold (its last judgement)
        self.low_mask = 0
        self.high_mask = 0
        self.direct_wake = True  # False: a sample reschedules through _wake (the tests')
        # sample lazily where no judgement can change (module docstring); False: a clock
        # event per sample, the reference of tests/tes/test_tes_lazy_analog.py
        self.lazy = True
        self._lazy: dict[int, _Channel] = {}  # the channels sampled lazily
        self._anchor = 0
        self._storage: Handle | None = None

    @property
    def now(self) -> int:
        return self._clock.now

    # --- power -------------------------------------------------------------

    def power_on(self, now: int) -> None:
        self._drop_lazy()  # the samples before are lost with the channels
        self.power_off()
        self._anchor = now
        for ch in self.channels.values():
            level, signal = ch.level, ch.signal
            self.channels[ch.number] = _Channel(
                ch.number, ch.slot, level, signal, bit=ch.bit, owner=self
            )
        self.low_mask = self.high_mask = 0
        for ch in self.channels.values():
            self._wake(ch, now)
        self.restart_storage(now)

    def power_off(self) -> None:
        self.sync(True)  # the samples up to now, then none
        self._drop_lazy()
        for ch in self.channels.values():
            if ch.handle is not None:
                ch.handle.cancel()
                ch.handle = None
        if self._storage is not None:
            self._storage.cancel()
            self._storage = None

    # --- field side --------------------------------------------------------

    def set_level(self, k: int, level: float, now: int) -> None:
        ch = self.channels[k]
        self._resume(ch, now)
        ch.level, ch.signal = level, None
        self._wake(ch, now)

    def set_signal(self, k: int, signal: AnalogSource, now: int) -> None:
        ch = self.channels[k]
        self._resume(ch, now)
        ch.signal = signal
        self._wake(ch, now)

    def level(self, k: int, now: int) -> float:
        ch = self.channels[k]
        return ch.signal.value_at(now) if ch.signal is not None else ch.level

    # --- acquisition -------------------------------------------------------

    def _wake(self, ch: _Channel, now: int) -> None:
        if ch.handle is not None or self._anchor > now:
            return
        period = self._period
        first = self._anchor + (ch.slot + 1) * SLOT
        at = first if now <= first else first + -(-(now - first) // period) * period
        ch.handle = self._clock.schedule(at, lambda t: self._sample(ch, t))

    def _points(self, ch: _Channel, now: int, params: Mapping[str, Value], keys: _Keys) -> float:
        """Electrical value -> 0..1023 points (§4.2.4), corrected (§4.2.5)."""
        full = self._full
        signal = ch.signal
        level = signal.value_at(now) if signal is not None else ch.level
        level = min(max(level, 0.0), full)  # the converter saturates
        raw = round_half_up(level / full * POINTS_MAX)
        zero, top = params[keys.corr_zero], params[keys.corr_full]
        assert isinstance(zero, int) and isinstance(top, int)
        corrected = raw + zero + (top - zero) * raw / POINTS_MAX
        return max(0.0, min(float(POINTS_MAX), corrected))

    def _take(self, ch: _Channel, now: int) -> float:
        """One sample of ``ch`` at ``now``: the point appended, the value averaged."""
        params, keys = self._params(), self._keys[ch.number]
        size = params[keys.filter]
        assert isinstance(size, int)
        point = self._points(ch, now, params, keys)
        samples = ch.samples
        if samples.maxlen != size:
            samples = ch.samples = deque(samples, maxlen=size)
        samples.append(point)
        # §4.2.3 average of the last N samples (AMB-TES-16: of those available at start)
        ch.sampled = self._scale(sum(samples) / len(samples), params, keys)
        ch.acquired = True
        return point

    def _sample(self, ch: _Channel, now: int) -> None:
        ch.handle = None
        params, keys = self._params(), self._keys[ch.number]
        size = params[keys.filter]
        assert isinstance(size, int)
        point = self._take(ch, now)
        samples = ch.samples
        self._judge_sampled(ch, now)
        # a signal may vary smoothly with no breakpoint (a sine): only a level settles
        signal = ch.signal
        # settled: the average is full of this one value (point == point: not NaN)
        if (
            (signal is None or isinstance(signal, Constant))
            and len(samples) == size
            and point == point
            and samples.count(point) == size
        ):
            return
        if self.lazy and ch.handle is None and self._anchor <= now and self._steady(ch):
            self._go_lazy(ch, now)
            return
        # the next slot of this channel: what _wake(ch, now + 1) finds, ``now`` being one
        # of its slots (anchor + (slot + 1) * SLOT + j * period) and no handle set
        if self.direct_wake and ch.handle is None and self._anchor <= now:
            ch.handle = self._clock.schedule(now + self._period, lambda t: self._sample(ch, t))
        else:
            self._wake(ch, now + 1)

    # --- lazy sampling -------------------------------------------------------------
    #
    # A sample of a channel changes its samples and value and judges it: its low and
    # high bits, its hysteresis, the alarm masks, then either the alarm latches or the
    # reflex outputs (``_judge_sampled``).  When the channel's thresholds are out of the
    # reach of every value it can take (``_steady``), its judgement is low = high =
    # False whatever it samples; with no alarm bit set anywhere the latches are left as
    # they are, and with its reflex outputs evaluated once since acquired nothing else
    # runs.  Its samples then change nothing but its value: they are taken when the
    # value is read (``_Channel.value``), before its input changes, before a threshold
    # write or another channel's alarm makes them matter (``_resume``), before a stored
    # value (strictly before the storage's instant: the storage was scheduled first),
    # and at the beat.  Only the last N samples (the filter) make the value, so a catch-
    # up takes at most N.

    def _steady(self, ch: _Channel) -> bool:
        if not ch.reflexed or self.low_mask or self.high_mask:
            return False
        signal = ch.signal
        if signal is None or isinstance(signal, Constant):
            return False  # settles within N samples anyway (and then stops)
        params, keys = self._params(), self._keys[ch.number]
        if params[keys.scale] == "on":
            lo, hi = params[keys.scale_min], params[keys.scale_max]
            assert isinstance(lo, int) and isinstance(hi, int)
            least = max(-32768, min(lo, hi))
            most = min(32767, max(lo, hi))
        else:
            least, most = 0, POINTS_MAX
        k = ch.number
        low, high = to_signed(self._word(0x023 + k)), to_signed(self._word(0x02B + k))
        return low <= least and high >= most  # value < low and value > high: never

    def _go_lazy(self, ch: _Channel, now: int) -> None:
        ch.behind = now
        if not self._lazy:
            Beat.of(self._clock).join(self)  # type: ignore[arg-type]
        self._lazy[ch.number] = ch

    def catch_up(self, ch: _Channel, until: int, present: bool) -> None:
        """The samples of lazy ``ch`` up to ``until`` (``present``: its instant too)."""
        period, behind = self._period, ch.behind
        due = (until - behind) // period if present else (until - 1 - behind) // period
        if due <= 0:
            return
        size = self._params()[self._keys[ch.number].filter]
        assert isinstance(size, int)
        for j in range(max(1, due - size + 1), due + 1):  # the last N make the value
            self._take(ch, behind + j * period)
        ch.behind = behind + due * period

    def sync(self, present: bool = False) -> None:
        """Every lazy channel caught up (the beat: before the present instant)."""
        now = self._clock.now
        for ch in self._lazy.values():
            self.catch_up(ch, now, present)

    def _resume(self, ch: _Channel, now: int) -> None:
        """A lazy ``ch`` caught up to now and sampled by clock events again."""
        if ch.behind < 0:
            return
        self.catch_up(ch, now, True)
        ch.handle = self._clock.schedule(ch.behind + self._period, lambda t: self._sample(ch, t))
        ch.behind = -1
        del self._lazy[ch.number]
        if not self._lazy:
            Beat.of(self._clock).leave(self)  # type: ignore[arg-type]

    def _resume_all(self, now: int) -> None:
        for ch in list(self._lazy.values()):
            self._resume(ch, now)

    def _drop_lazy(self) -> None:
        for ch in self._lazy.values():
            ch.behind = -1
        if self._lazy:
            self._lazy.clear()
            Beat.of(self._clock).leave(self)  # type: ignore[arg-type]

    def _scale(self, points: float, params: Mapping[str, Value], keys: _Keys) -> int:
        """§4.2.4 points 0..1023 -> final value (AMB-TES-18: linear, rounded)."""
        if params[keys.scale] != "on":
            return round_half_up(points)
        lo, hi = params[keys.scale_min], params[keys.scale_max]
        assert isinstance(lo, int) and isinstance(hi, int)
        return max(-32768, min(32767, round_half_up(lo + (hi - lo) * points / POINTS_MAX)))

    # --- thresholds (§4.2.6) -----------------------------------------------

    def evaluate(self, now: int) -> None:
        """Recompute threshold bits and reflex outputs of every acquired channel
        (after a master write of a threshold, an output or the polarity)."""
        self._resume_all(now)  # their judgement may change from here on
        for ch in self.channels.values():
            if ch.acquired:
                self._judge(ch)
        self._on_evaluate(now)

    def _judge_sampled(self, ch: _Channel, now: int) -> None:
        """After a sample: only ``ch`` changed.  Every other channel's bits are those of
        its last judgement (its value and the thresholds are unchanged since: a
        threshold write runs ``evaluate``), and judging again leaves them as they are.

        When ``ch`` had been evaluated since acquired and its low, high and hysteresis
        states came out as they were, the reflex outputs are those the last evaluation
        gave (they depend on these states, the threshold output words and the polarity,
        and a write of those runs ``evaluate``): only the alarm latches are set again
        (the master may have reset them since)."""
        before = (ch.low, ch.high, ch.hysteresis)
        self._judge(ch)
        if (self.low_mask or self.high_mask) and self._lazy:
            self._resume_all(now)  # an alarm bit: every sample latches it again from now
        latch = self._on_latch
        if latch is not None and ch.reflexed and before == (ch.low, ch.high, ch.hysteresis):
            latch()
        else:
            ch.reflexed = True
            self._on_evaluate(now)

    def _judge(self, ch: _Channel) -> None:
        k, bit = ch.number, ch.bit
        low = ch.low = ch.sampled < to_signed(self._word(0x023 + k))
        high = ch.high = ch.sampled > to_signed(self._word(0x02B + k))
        self.low_mask = self.low_mask | bit if low else self.low_mask & ~bit
        self.high_mask = self.high_mask | bit if high else self.high_mask & ~bit
        if high:
            ch.hysteresis = True  # §4.2.6.2 set above the high threshold
        elif low:
            ch.hysteresis = False  # ... reset under the low threshold

    def reflex(self) -> dict[int, bool]:
        """Output number -> threshold state, before polarity (AMB-TES-20/21)."""
        out: dict[int, bool] = {}
        for ch in self.channels.values():
            if not ch.acquired:
                continue
            word = self._word(0x033 + ch.number)
            high_out, low_out = word >> 8, word & 0xFF
            if high_out == low_out and high_out < 4:
                out[high_out] = ch.hysteresis
                continue
            if high_out < 4:
                out[high_out] = ch.high
            if low_out < 4:
                out[low_out] = ch.low
        return out

    # --- storage (§4.2.2, §6.4.13) -----------------------------------------

    def restart_storage(self, now: int) -> None:
        if self._storage is not None:
            self._storage.cancel()
            self._storage = None
        period = self._word(0x055) * 1_000 * MS  # Tb = 1 s; 0 = no storage
        if period:
            self._storage = self._clock.schedule(now + period, self._store)

    def _store(self, now: int) -> None:
        self.sync()  # the samples before now (a sample at now comes after: scheduled later)
        for ch in self.channels.values():
            ch.history.appendleft(ch.sampled)  # AMB-TES-15: newest at the lowest address
        self._storage = None
        self.restart_storage(now)

    def history(self, k: int, j: int) -> int:
        ch = self.channels.get(k)
        if ch is None or j >= len(ch.history):
            return 0
        return ch.history[j] & 0xFFFF


def dac_points(word: int, params: Mapping[str, Value], k: int) -> int:
    """§4.3.1 an analog output word -> converter points 0..32767."""
    value = to_signed(word)
    if params[f"ao{k}.scale"] == "on":
        lo, hi = params[f"ao{k}.scale_min"], params[f"ao{k}.scale_max"]
        assert isinstance(lo, int) and isinstance(hi, int)
        value = round_half_up((value - lo) * DAC_MAX / (hi - lo))
    return max(0, min(DAC_MAX, value))
