"""Two thresholds per channel and their detection bits Ixy,0..F (AEM 2.3-5, 4.3).

A bit goes to 1 when the measurement is >= threshold + h/2 and back to 0 when it
is <= threshold - h/2 (AEM 2.3-5, AMB-AEM-09); between the two it keeps its
state.  The comparison is made each time a new value of the channel is
acquired; an inhibited channel's bits are forced to 0.  Threshold 0 of channel
i is bit i, threshold 1 is bit 8 + i (AEM 2.4-2).
"""

from __future__ import annotations

from collections.abc import Sequence

from fieldtwin.errors import ConfigError
from fieldtwin.words import bytes_to_words, to_signed, words_to_bytes

LEVELS = 2
THRESHOLD_BYTES = 16  # AEM 4.3-1: 8 words, channel 0 first


class ThresholdDetector:
    """The 16 thresholds and the 16 detection bits."""

    __slots__ = ("bits", "values")

    def __init__(self) -> None:
        self.values: list[list[int]] = [[0] * 8 for _ in range(LEVELS)]  # AEM 4.3-1: 0
        self.bits = 0

    def write(self, level: int, values: Sequence[int]) -> None:
        if len(values) != 8:
            raise ConfigError(f"threshold {level}: {len(values)} values (allowed exactly 8)")
        for value in values:
            if not -32768 <= value <= 32767:
                raise ConfigError(f"threshold {value} out of range (allowed -32768..32767)")
        self.values[level] = list(values)

    def write_table(self, level: int, data: bytes) -> None:
        """The 16-byte table of request 2 or 4."""
        self.values[level] = [to_signed(w) for w in bytes_to_words(data)]

    def table(self, level: int) -> bytes:
        """The 16-byte answer to request 3 or 5."""
        return words_to_bytes(v & 0xFFFF for v in self.values[level])

    def compare(self, channel: int, measurement: int, h: int) -> None:
        """AEM 2.3-5: update both bits of ``channel`` with hysteresis ``h``."""
        half = h // 2  # every tabulated h is even
        for level in range(LEVELS):
            bit = 1 << (channel + 8 * level)
            threshold = self.values[level][channel]
            if measurement >= threshold + half:
                self.bits |= bit
            elif measurement <= threshold - half:
                self.bits &= ~bit

    def force_off(self, channel: int) -> None:
        """AEM 4.3-2: an inhibited channel's detection bits are 0."""
        self.bits &= ~((1 << channel) | (1 << (channel + 8)))

    def reset(self) -> None:
        self.values = [[0] * 8 for _ in range(LEVELS)]
        self.bits = 0
