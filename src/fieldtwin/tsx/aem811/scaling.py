"""From a converter reading to the measurement the PLC reads (AEM 2.3-1 .. 2.3-5).

The order of the processing is the manual's: the reading is held inside the
extended range ELL..EHL (beyond it the limit is delivered and the ELL/EHL fault
set, AEM 2.3-1), standardized to 0..10000 (or -10000..10000 for a bipolar
range), its square root taken where the scaling allows it (AEM 2.3-2), then
expressed in the chosen scaling (AEM 2.3-3).
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

from fieldtwin.tsx.aem811.ranges import RANGES, InputRange, round_half_away

WORD_MIN, WORD_MAX = -32768, 32767
FULL = 10000  # 100.00 %


class Scaling(enum.IntEnum):
    """AEM 3.2-2: the second 4-bit byte of the mode word."""

    INPUT_RANGE = 0xA
    STANDARD = 0xB
    USER = 0xC


@dataclass(frozen=True, slots=True)
class ChannelConfig:
    """One channel's operating mode (AEM 3.2-2), limits only for User range scaling."""

    range_number: int = 0
    sqrt: bool = False
    scaling: Scaling = Scaling.INPUT_RANGE
    continuity: bool = False
    high: int = 0
    low: int = 0

    @property
    def range(self) -> InputRange:
        return RANGES[self.range_number]

    @property
    def mode_word(self) -> int:
        """AEM 3.2-2 / AMB-AEM-01: H'[range][processing][scaling][test]'."""
        return (
            (self.range_number << 12)
            | (int(self.sqrt) << 8)
            | (int(self.scaling) << 4)
            | int(self.continuity)
        )

    def zone_words(self, channel: int) -> list[int]:
        """The channel's configuration zone: 2 words, or 4 with the user limits."""
        words = [0x00C0 | channel, self.mode_word]
        if self.scaling is Scaling.USER:
            words += [self.high & 0xFFFF, self.low & 0xFFFF]
        return words


DEFAULT_CHANNEL = ChannelConfig()  # AEM 3.3: H'00A0', -10/+10 V, input range scaling


@dataclass(frozen=True, slots=True)
class Measurement:
    """One processed acquisition: the value and the channel's fault conditions."""

    value: int
    below: bool = False  # ELL exceeded (fault bit 32 + 4i)
    continuity: bool = False  # continuity fault (33 + 4i)
    overflow: bool = False  # calculation error (34 + 4i)
    above: bool = False  # EHL exceeded (35 + 4i)

    @property
    def faulty(self) -> bool:
        return self.below or self.continuity or self.overflow or self.above


def measure(
    mv: float | None, cfg: ChannelConfig, *, quantize: bool = True, tested: bool = False
) -> Measurement:
    """Terminal millivolts (None: open input) -> the measurement (AEM 2.3).

    ``tested``: the continuity test runs on this acquisition (AEM 2.3-4).
    """
    rng = cfg.range
    if mv is None:
        # AEM 2.3-4: an open voltage input reads EHL; the test, if run, says so.
        # A current range has its 100 ohm resistor: an open line reads 0 mA.
        if not rng.current:
            value, overflow = scale(rng.ehl, cfg)
            return Measurement(value, continuity=tested, overflow=overflow)
        mv = 0.0
    x = mv * rng.unit_per_mv()
    code = rng.code(x)
    below, above = code < rng.code(rng.ell), code > rng.code(rng.ehl)
    if below or above:  # AEM 2.3-1: the limit is delivered, ELL/EHL fault set
        x = float(rng.ell if below else rng.ehl)
    elif quantize:
        x = rng.from_code(code)  # AEM 8.2: 11000/32768 mV steps
    value, overflow = scale(x, cfg)
    return Measurement(value, below=below, overflow=overflow, above=above)


def standardize(x: float, rng: InputRange) -> float:
    """AEM 2.3-3 standard range: 0 % at LL, 100.00 % at HL; bipolar -100 %..+100 %."""
    if rng.bipolar:
        return x * FULL / rng.high
    return (x - rng.low) * FULL / (rng.high - rng.low)


def square_root(p: float) -> float:
    """AEM 2.3-2: +100 x sqrt(m) for m >= 0, -100 x sqrt(-m) for m < 0."""
    return math.copysign(100.0 * math.sqrt(abs(p)), p)


def scale(x: float, cfg: ChannelConfig) -> tuple[int, bool]:
    """A value in the range unit -> (measurement, calculation overflow)."""
    rng = cfg.range
    if cfg.scaling is Scaling.INPUT_RANGE:
        return round_half_away(x), False  # AEM 2.3-3: value = mV or µA
    p = standardize(x, rng)
    if cfg.sqrt:  # AEM 2.3-2: after standardizing, before the user scale
        p = square_root(p)
    if cfg.scaling is Scaling.STANDARD:
        return round_half_away(p), False
    origin = -FULL if rng.bipolar else 0
    span = 2 * FULL if rng.bipolar else FULL
    result = round_half_away(cfg.low + (p - origin) * (cfg.high - cfg.low) / span)
    if result > WORD_MAX or result < WORD_MIN:  # AMB-AEM-18: saturate, overflow bit
        return (WORD_MAX if result > WORD_MAX else WORD_MIN), True
    return result, False


def extended_zone(cfg: ChannelConfig) -> tuple[int, int]:
    """The measurements at ELL and EHL (AEM 2.3-3 extended zones)."""
    rng = cfg.range
    return scale(rng.ell, cfg)[0], scale(rng.ehl, cfg)[0]


def hysteresis(cfg: ChannelConfig) -> int:
    """AEM 2.3-5: h for the channel's range and scaling (manual-notes AMB-AEM-11)."""
    if cfg.scaling is Scaling.INPUT_RANGE:
        return cfg.range.hysteresis
    if cfg.scaling is Scaling.STANDARD:
        return 50
    # 2 x (Integer of ((HL - LL) x 25.10^-4) + 1), with the user limits
    return 2 * ((abs(cfg.high - cfg.low) * 25) // 10000 + 1)
