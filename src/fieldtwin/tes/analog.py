"""Analog inputs (§4.2) and outputs (§4.3) of the TES 4EA, 4SA, 8EA, 8ESA, 8SA-U.

Acquisition runs one channel every 8 ms in turn (§4.2.1).  A channel whose
input is constant and whose average is full of that value stops sampling
until its input changes (DESIGN rule 3): idle analog TES cost nothing.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Protocol

from fieldtwin.clock import MS, Handle, SimClock
from fieldtwin.signals import Constant
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
    value: int = 0  # filtered and scaled (signed)
    acquired: bool = False
    low: bool = False
    high: bool = False
    hysteresis: bool = False  # §4.2.6.2 reflex output state
    history: deque[int] = field(default_factory=lambda: deque(maxlen=HISTORY_LENGTH))
    bit: int = 0  # 1 << number, for the alarm masks
    reflexed: bool = False  # its judgement since acquired went through an evaluation


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
            k: _Channel(k, slot, bit=1 << k) for slot, k in enumerate(model.analog_inputs)
        }
        self._keys = {k: _Keys.of(k) for k in model.analog_inputs}
        self._period = model.analog_slots * SLOT
        self._full = model.analog_range.full_scale
        # bit k: channel k under its low / over its high threshold (its last judgement)
        self.low_mask = 0
        self.high_mask = 0
        self.direct_wake = True  # False: a sample reschedules through _wake (the tests')
        self._anchor = 0
        self._storage: Handle | None = None

    # --- power -------------------------------------------------------------

    def power_on(self, now: int) -> None:
        self.power_off()
        self._anchor = now
        for ch in self.channels.values():
            level, signal = ch.level, ch.signal
            self.channels[ch.number] = _Channel(ch.number, ch.slot, level, signal, bit=ch.bit)
        self.low_mask = self.high_mask = 0
        for ch in self.channels.values():
            self._wake(ch, now)
        self.restart_storage(now)

    def power_off(self) -> None:
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
        ch.level, ch.signal = level, None
        self._wake(ch, now)

    def set_signal(self, k: int, signal: AnalogSource, now: int) -> None:
        ch = self.channels[k]
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

    def _sample(self, ch: _Channel, now: int) -> None:
        ch.handle = None
        params, keys = self._params(), self._keys[ch.number]
        size = params[keys.filter]
        assert isinstance(size, int)
        point = self._points(ch, now, params, keys)
        samples = ch.samples
        if samples.maxlen != size:
            samples = ch.samples = deque(samples, maxlen=size)
        samples.append(point)
        # §4.2.3 average of the last N samples (AMB-TES-16: of those available at start)
        ch.value = self._scale(sum(samples) / len(samples), params, keys)
        ch.acquired = True
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
        # the next slot of this channel: what _wake(ch, now + 1) finds, ``now`` being one
        # of its slots (anchor + (slot + 1) * SLOT + j * period) and no handle set
        if self.direct_wake and ch.handle is None and self._anchor <= now:
            ch.handle = self._clock.schedule(now + self._period, lambda t: self._sample(ch, t))
        else:
            self._wake(ch, now + 1)

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
        latch = self._on_latch
        if latch is not None and ch.reflexed and before == (ch.low, ch.high, ch.hysteresis):
            latch()
        else:
            ch.reflexed = True
            self._on_evaluate(now)

    def _judge(self, ch: _Channel) -> None:
        k, bit = ch.number, ch.bit
        low = ch.low = ch.value < to_signed(self._word(0x023 + k))
        high = ch.high = ch.value > to_signed(self._word(0x02B + k))
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
        for ch in self.channels.values():
            ch.history.appendleft(ch.value)  # AMB-TES-15: newest at the lowest address
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
