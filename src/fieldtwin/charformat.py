"""A serial character format: baud rate, data bits, parity, stop bits.

The one value the Modbus timing (TES 7.2.7), the transports (pyserial settings)
and the SCM line (SCM 3.2) share.  A character takes 1 start bit + the data
bits + the parity bit if any + the stop bits on the line.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from fractions import Fraction

from fieldtwin.errors import ConfigError

US_PER_S = 1_000_000


class Parity(enum.Enum):
    """None, odd or even, by the letter the usual notation (``9600 8N1``) writes."""

    NONE = "N"
    ODD = "O"
    EVEN = "E"

    @property
    def letter(self) -> str:
        return self.value

    @classmethod
    def parse(cls, text: str, where: str = "parity") -> Parity:
        """'N', 'E', 'O' (any case; 'none', 'even', 'odd' too) -> Parity."""
        key = text.strip().upper()
        for member in cls:
            if key in (member.value, member.name):
                return member
        raise ConfigError(f"{where}: {text!r} not allowed (allowed: N, E, O)")


DATA_BITS = (5, 6, 7, 8)
STOP_BITS = (1, 2)


@dataclass(frozen=True, slots=True)
class CharFormat:
    """``CharFormat(9600, 8, Parity.NONE, 1)`` is 9600 8N1."""

    baud: int = 9600
    data_bits: int = 8
    parity: Parity = Parity.NONE
    stop_bits: int = 1

    def __post_init__(self) -> None:
        if isinstance(self.baud, bool) or not isinstance(self.baud, int) or self.baud <= 0:
            raise ConfigError(f"baud {self.baud!r}: must be a whole number > 0")
        if self.data_bits not in DATA_BITS:
            raise ConfigError(f"data bits {self.data_bits!r}: allowed 5, 6, 7 or 8")
        if not isinstance(self.parity, Parity):
            raise ConfigError(f"parity {self.parity!r}: allowed N, E or O")
        if self.stop_bits not in STOP_BITS:
            raise ConfigError(f"stop bits {self.stop_bits!r}: allowed 1 or 2")

    @property
    def bits(self) -> int:
        """Bits per character on the line: start + data + parity + stop."""
        return 1 + self.data_bits + (self.parity is not Parity.NONE) + self.stop_bits

    @property
    def mask(self) -> int:
        """The data bits of a character."""
        return (1 << self.data_bits) - 1

    @property
    def char_time(self) -> Fraction:
        """One character's duration in microseconds, exactly."""
        return Fraction(self.bits * US_PER_S, self.baud)

    @property
    def char_time_us(self) -> int:
        """One character's duration in whole microseconds (never less than 1)."""
        return max(1, round(self.bits * US_PER_S / self.baud))

    def with_baud(self, baud: int) -> CharFormat:
        return CharFormat(baud, self.data_bits, self.parity, self.stop_bits)

    @property
    def frame(self) -> str:
        """'8N1': the format without the speed."""
        return f"{self.data_bits}{self.parity.letter}{self.stop_bits}"

    def __str__(self) -> str:
        return f"{self.baud} {self.frame}"


LINE_DATA_BITS = (7, 8)  # what a transport's serial line takes


def line_settings(
    baud: int = 9600, data_bits: int = 8, parity: str | Parity = "N", stop_bits: int = 1
) -> CharFormat:
    """A transport's character format, checked: 7 or 8 data bits, parity N/E/O, 1 or 2 stops."""
    if isinstance(baud, bool) or not isinstance(baud, int) or baud <= 0:
        raise ConfigError(f"line setting baud={baud!r}: allowed a whole number > 0")
    if data_bits not in LINE_DATA_BITS:
        raise ConfigError(f"line setting data_bits={data_bits!r}: allowed 7 or 8")
    if not isinstance(parity, Parity):
        if parity not in tuple(p.value for p in Parity):
            raise ConfigError(f"line setting parity={parity!r}: allowed N, E or O")
        parity = Parity(parity)
    if stop_bits not in STOP_BITS:
        raise ConfigError(f"line setting stop_bits={stop_bits!r}: allowed 1 or 2")
    return CharFormat(baud, data_bits, parity, stop_bits)


__all__ = ["DATA_BITS", "LINE_DATA_BITS", "STOP_BITS", "CharFormat", "Parity", "line_settings"]
