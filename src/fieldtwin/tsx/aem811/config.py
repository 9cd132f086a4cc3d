"""The module configuration: zone 1 (sampling period) and zones 2..9 (channels).

AEM 3.2: zone 1 is H'00A0' and the period N (x 100 ms, 8..32000); a channel zone
is H'00Cn', the mode word, and for User range scaling the higher and lower
limits.  AEM 3.4-3: 2 to 34 words, whole zones in any order, and the rules
that make the module refuse a configuration (it then keeps the previous one).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

from fieldtwin.tsx.aem811.ranges import RANGES
from fieldtwin.tsx.aem811.scaling import DEFAULT_CHANNEL, ChannelConfig, Scaling
from fieldtwin.words import bytes_to_words, format_hex, to_signed

CHANNELS = 8
PERIOD_ID = 0x00A0  # AEM 3.2-1
CHANNEL_ID = 0x00C0  # AEM 3.2-2: H'00Cn'
PERIOD_MIN, PERIOD_MAX = 8, 32000  # AEM 3.2-1: N x 100 ms
CONTINUITY_MIN_PERIOD = 24  # AEM 3.2-1: less than 24 is incompatible (AMB-AEM-08)
CONFIG_MIN_BYTES, CONFIG_MAX_BYTES = 4, 68  # AEM 3.4-3: 2 to 34 words
DEFAULT_PERIOD = 10  # AEM 3.3


@dataclass(frozen=True, slots=True)
class ModuleConfig:
    period: int = DEFAULT_PERIOD
    channels: tuple[ChannelConfig, ...] = (DEFAULT_CHANNEL,) * CHANNELS

    def words(self) -> list[int]:
        """The whole configuration as the module sends it back (H'41')."""
        words = self.zone1()
        for channel, cfg in enumerate(self.channels):
            words += cfg.zone_words(channel)
        return words

    def zone1(self) -> list[int]:
        return [PERIOD_ID, self.period]


DEFAULT_CONFIG = ModuleConfig()


@dataclass(frozen=True, slots=True)
class Rejection:
    """Why the module refused a configuration (AEM 3.4-3); shown in the status."""

    reason: str


def decode_mode(word: int) -> ChannelConfig | Rejection:
    """AEM 3.2-2 mode word -> the channel's mode (limits not yet known)."""
    range_number, processing = (word >> 12) & 0xF, (word >> 8) & 0xF
    scaling, test = (word >> 4) & 0xF, word & 0xF
    if range_number >= len(RANGES):
        return Rejection(f"mode {format_hex(word)}: input range {range_number} (allowed 0..8)")
    if processing > 1:
        return Rejection(f"mode {format_hex(word)}: processing {processing} (allowed 0, 1)")
    if scaling not in tuple(Scaling):
        return Rejection(f"mode {format_hex(word)}: scaling {scaling:X} (allowed A, B, C)")
    if test > 1:
        return Rejection(f"mode {format_hex(word)}: continuity test {test} (allowed 0, 1)")
    cfg = ChannelConfig(range_number, bool(processing), Scaling(scaling), bool(test))
    if cfg.sqrt and cfg.scaling is Scaling.INPUT_RANGE:
        return Rejection(f"mode {format_hex(word)}: square root with input range scaling")
    if cfg.continuity and cfg.range.current:
        return Rejection(f"mode {format_hex(word)}: continuity test on a current range")
    return cfg


def parse_configuration(data: bytes, current: ModuleConfig) -> ModuleConfig | Rejection:
    """A write-configuration table (H'40') -> the new configuration, or why not."""
    if not CONFIG_MIN_BYTES <= len(data) <= CONFIG_MAX_BYTES or len(data) % 2:
        return Rejection(f"length {len(data)} bytes (allowed 4..68, whole words)")
    words = bytes_to_words(data)
    period = current.period
    channels = list(current.channels)
    seen: set[int] = set()
    index = 0
    while index < len(words):
        ident = words[index]
        if ident in seen:
            return Rejection(f"zone {format_hex(ident)} sent twice")
        seen.add(ident)
        if ident == PERIOD_ID:
            result = _period_zone(words, index)
            if isinstance(result, Rejection):
                return result
            period, index = result, index + 2
        elif ident & 0xFFF8 == CHANNEL_ID:
            zone = _channel_zone(words, index)
            if isinstance(zone, Rejection):
                return zone
            channels[ident & 7] = zone
            index += 4 if zone.scaling is Scaling.USER else 2
        else:
            return Rejection(f"word {index}: {format_hex(ident)} is not a zone identifier")
    return _compatible(ModuleConfig(period, tuple(channels)))


def _period_zone(words: Sequence[int], index: int) -> int | Rejection:
    if index + 2 > len(words):
        return Rejection("zone H'00A0' cut short (2 words)")
    period = words[index + 1]
    if not PERIOD_MIN <= period <= PERIOD_MAX:
        return Rejection(f"sampling period {period} (allowed 8..32000 x 100 ms)")
    return period


def _channel_zone(words: Sequence[int], index: int) -> ChannelConfig | Rejection:
    ident = words[index]
    if index + 2 > len(words):
        return Rejection(f"zone {format_hex(ident)} cut short")
    cfg = decode_mode(words[index + 1])
    if isinstance(cfg, Rejection) or cfg.scaling is not Scaling.USER:
        return cfg
    if index + 4 > len(words):
        return Rejection(f"zone {format_hex(ident)}: user range needs its two limits")
    high, low = to_signed(words[index + 2]), to_signed(words[index + 3])
    if high == low:
        return Rejection(f"zone {format_hex(ident)}: higher and lower limits both {high}")
    return replace(cfg, high=high, low=low)


def _compatible(config: ModuleConfig) -> ModuleConfig | Rejection:
    # AEM 3.4-3: the continuity test is incompatible with a period under 2.4 s
    if config.period < CONTINUITY_MIN_PERIOD:
        for channel, cfg in enumerate(config.channels):
            if cfg.continuity:
                return Rejection(
                    f"channel {channel}: continuity test with a period of {config.period}"
                    " (needs 24 or more)"
                )
    return config


def read_configuration(config: ModuleConfig, request: bytes, capacity: int) -> list[int]:
    """AEM 4.4-3: the words answered to H'41'.

    A first transmitted word H'XXCi' (X any value) asks for channel i's zone
    after zone 1; no transmission table, or a first word that is not H'XXC0' to
    H'XXC7', asks for the complete configuration (the footnote (*): "the first word
    ... should be different from codes H'XXC0' to H'XXC7' ... if a transmission
    length is defined").  A single byte is not a word: the complete configuration.
    """
    first = bytes_to_words(request)[0] if len(request) >= 2 else None
    if first is not None and first & 0xF8 == CHANNEL_ID:  # H'XXCi', X = any value
        channel = first & 7
        return config.zone1() + config.channels[channel].zone_words(channel)
    words = config.words()
    # TSX 47-20 text: a table too short for the whole configuration gets zone 1
    return words if 2 * len(words) <= capacity else config.zone1()
