"""The channel configuration tables (SCM 3.2): 8 words half-duplex, 9 words full-duplex.

Values are BCD, codes hexadecimal; each 4-bit field is a nibble of its word
(nibble 3 = bits F..C).  A table that breaks a limit is refused: the write
configuration request answers H'FD' and the channel is left unconfigured
(SCM 3.3 "any previous configuration is lost").
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

from fieldtwin.charformat import CharFormat, Parity
from fieldtwin.clock import MS
from fieldtwin.tsx.scm.line import ALLOWED_FRAMES, allowed
from fieldtwin.words import bcd_encode, bytes_to_words, is_bcd, nibble, words_to_bytes

HALF_DUPLEX_BYTES = 16  # SCM 3.2: 8 words
FULL_DUPLEX_BYTES = 18  # SCM 3.2: 9 words
ECHO_TIMEOUT_BASE_US = 50 * MS  # SCM 3.2 "A 50 millisecond time base is used"
ECHO_RETRIES = 3  # SCM 3.2 "the character is sent again and 3 more tries are made"

# SCM 3.2 "Parity: 0 no parity, 1 odd parity, 2 even parity" -> the kernel's Parity
PARITY_CODES = {0: Parity.NONE, 1: Parity.ODD, 2: Parity.EVEN}

# SCM 3.2 speed lists (AMB-SCM-02: taken literally); 19200 is coded H'1920' (AMB-SCM-03)
SPEEDS = {
    0: (19200, 9600, 4800, 2400, 1200, 600, 300, 150),
    1: (19200, 9600, 4800, 2400, 1200, 600, 300, 75),
}


class Function(enum.Enum):
    """SCM 3.2 "Function": the channel operating mode."""

    HALF_DUPLEX = 0
    FULL_DUPLEX = 1


@dataclass(frozen=True, slots=True)
class EndChars:
    """Up to two end characters (ERC or ETC) with their validation and include flags."""

    valid1: bool = False
    incl1: bool = False
    char1: int = 0
    valid2: bool = False
    incl2: bool = False
    char2: int = 0

    def match(self, value: int) -> int:
        """1 or 2 if ``value`` is a validated end character, else 0 (1 is checked first)."""
        if self.valid1 and value == self.char1:
            return 1
        if self.valid2 and value == self.char2:
            return 2
        return 0

    def included(self, which: int) -> bool:
        return self.incl1 if which == 1 else self.incl2


@dataclass(frozen=True, slots=True)
class ChannelConfig:
    """A decoded, accepted channel configuration."""

    function: Function
    fmt: CharFormat  # speed included (SCM 3.2 "transmission speed")
    rx_echo: bool = False
    auto_lf: bool = False
    xon_xoff_tx: bool = False
    back_space: bool = False
    erc: EndChars = EndChars()
    etc: EndChars = EndChars()
    # half-duplex only
    tx_echo: bool = False
    tx_echo_timeout: int = 0  # in 50 ms units
    # full-duplex only
    dtr_auto: bool = False
    xon_xoff_rx: bool = False
    echo_type: int = 0
    silence_chars: int = 0
    words: tuple[int, ...] = ()  # the table as written, for read configuration (6.3)

    @property
    def baud(self) -> int:
        return self.fmt.baud

    @property
    def full_duplex(self) -> bool:
        return self.function is Function.FULL_DUPLEX

    @property
    def echo_timeout_us(self) -> int:
        return self.tx_echo_timeout * ECHO_TIMEOUT_BASE_US

    def table_bytes(self) -> bytes:
        return words_to_bytes(self.words)


class Refused(Exception):
    """Why a table is refused (becomes report H'FD', never leaves the module)."""


def _flag(word: int, index: int, what: str) -> bool:
    value = nibble(word, index)
    if value > 1:
        raise Refused(f"{what} = {value} (allowed 0 or 1)")
    return bool(value)


def decode_speed(word: int, channel: int) -> int:
    if not is_bcd(word):
        raise Refused(f"speed {word:04X} is not BCD")
    baud = 19200 if word == 0x1920 else int(f"{word:04X}")
    if baud not in SPEEDS[channel]:
        raise Refused(f"speed {baud} not in the channel {channel} list {SPEEDS[channel]}")
    return baud


def decode_format(word: int, speed: int, channel: int) -> tuple[Function, CharFormat]:
    """Words 1 and 2 of a table: function and character format, then the speed."""
    function, data_bits, parity, stop = (nibble(word, i) for i in (3, 2, 1, 0))
    if function > 1 or parity not in PARITY_CODES:
        raise Refused(f"function {function} / parity {parity} out of range")
    frame = f"{data_bits}{PARITY_CODES[parity].letter}{stop}"
    if frame not in ALLOWED_FRAMES:
        raise Refused(f"character format {frame} is not one of the eight allowed")
    fmt = CharFormat(decode_speed(speed, channel), data_bits, PARITY_CODES[parity], stop)
    assert allowed(fmt)
    return Function(function), fmt


def _end_chars(flags: int, chars: int, fmt: CharFormat, what: str) -> EndChars:
    c1, c2 = chars >> 8, chars & 0xFF
    ends = EndChars(
        _flag(flags, 3, f"VAL-{what}-1"),
        _flag(flags, 2, f"{what}-1-INCL"),
        c1,
        _flag(flags, 1, f"VAL-{what}-2"),
        _flag(flags, 0, f"{what}-2-INCL"),
        c2,
    )
    # SCM 3.2: H'00'..H'7F' for 7 bit characters
    if (ends.valid1 and c1 > fmt.mask) or (ends.valid2 and c2 > fmt.mask):
        raise Refused(f"{what} character does not fit {fmt.data_bits} bits")
    return ends


def decode(data: bytes, channel: int, full_duplex_allowed: bool) -> ChannelConfig:
    """A write-configuration table -> ChannelConfig; Refused names the broken limit."""
    if len(data) not in (HALF_DUPLEX_BYTES, FULL_DUPLEX_BYTES):
        raise Refused(f"TXTi,L = {len(data)} (allowed 16 or 18)")  # SCM 3.3
    w = bytes_to_words(data)
    function, fmt = decode_format(w[0], w[1], channel)
    expected = FULL_DUPLEX_BYTES if function is Function.FULL_DUPLEX else HALF_DUPLEX_BYTES
    if len(data) != expected:
        raise Refused(f"function {function.value} needs a table of {expected} bytes")
    if function is Function.FULL_DUPLEX and not full_duplex_allowed:
        raise Refused(f"full-duplex is not available on channel {channel}")  # SCM 4.4
    common = {
        "function": function,
        "fmt": fmt,
        "rx_echo": _flag(w[3], 3, "Rec. echo"),
        "auto_lf": _flag(w[3], 2, "Auto-LF"),
        "xon_xoff_tx": _flag(w[3], 1, "Xon-Xoff (T)"),
        "back_space": _flag(w[3], 0, "Back-Space"),
        "erc": _end_chars(w[4], w[5], fmt, "ERC"),
        "etc": _end_chars(w[6], w[7], fmt, "ETC"),
        "words": tuple(w),
    }
    if function is Function.HALF_DUPLEX:
        return ChannelConfig(**common, **_half_duplex(w[2]))  # type: ignore[arg-type]
    return ChannelConfig(**common, **_full_duplex(w[2], w[8]))  # type: ignore[arg-type]


def _half_duplex(word: int) -> dict[str, object]:
    echo = _flag(word, 3, "Trans. echo")
    timeout = word & 0x0FFF
    if echo and (not is_bcd(timeout) or timeout == 0):
        # AMB-SCM-24: 3 BCD digits, 1 to 999 time-base increments when the echo is on
        raise Refused(f"transmission echo time-out {timeout:03X} (allowed BCD 001..999)")
    return {"tx_echo": echo, "tx_echo_timeout": int(f"{timeout:03X}") if echo else 0}


def _full_duplex(word: int, silence: int) -> dict[str, object]:
    if nibble(word, 3) != 0:
        raise Refused("full-duplex word 3, first field must be 0")
    if not is_bcd(silence):
        raise Refused(f"silence {silence:04X} is not BCD")
    return {
        "dtr_auto": _flag(word, 2, "DTR control"),
        "xon_xoff_rx": _flag(word, 1, "Xon-Xoff (Rec.)"),
        "echo_type": int(_flag(word, 0, "Echo type")),
        "silence_chars": int(f"{silence:04X}"),
    }


def speed_conflict(a: int, b: int) -> bool:
    """SCM 3.2 restrictions when both channels are used simultaneously."""
    for one, other in ((a, b), (b, a)):
        if one == 19200 and other > 4800:
            return True
        if one == 9600 and other > 9600:
            return True
    return False


def encode_speed(baud: int) -> int:
    return 0x1920 if baud == 19200 else bcd_encode(baud)
