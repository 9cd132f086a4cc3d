"""The 9 input ranges of the TSX AEM 811 and the converter behind them.

AEM 2.3-1: each range has a normal zone LL..HL and an extended zone ELL..EHL
(the conversion capacity); AEM 2.3-3 gives them in the range's own unit, mV for
the voltage ranges and µA for the current ranges (read through the 100 ohm
resistor fitted in the terminal block, AEM 6.3-4).  AEM 8.2: the converter
covers +/- 11 V in 32768 steps a side, 11000/32768 mV = 0.33 mV at best.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

SHUNT_OHMS = 100  # AEM 2.3-1 (*), 6.3-4: current inputs through 100 ohm
LSB_MV = 11000 / 32768  # AEM 1.2-1, 8.2: maximum resolution 0.33 mV
CODES_PER_MV = 32768 / 11000


def round_half_away(value: float) -> int:
    """The module's integer result: halves away from zero (manual-notes AMB-AEM-19)."""
    magnitude = math.floor(abs(value) + 0.5)
    return int(magnitude if value >= 0 else -magnitude)


@dataclass(frozen=True, slots=True)
class InputRange:
    """One line of the AEM 2.3-1 / 2.3-3 tables, in the range's unit (mV or µA)."""

    number: int
    name: str
    current: bool
    low: int  # LL
    high: int  # HL
    ell: int  # extended range lower limit
    ehl: int  # extended range higher limit
    hysteresis: int  # AEM 2.3-5 table, input range scaling

    @property
    def unit(self) -> str:
        return "µA" if self.current else "mV"

    @property
    def bipolar(self) -> bool:
        return self.low < 0

    def unit_per_mv(self) -> float:
        """Range units per terminal millivolt (µA = mV / 100 ohm x 1000)."""
        return 1000 / SHUNT_OHMS if self.current else 1.0

    def to_mv(self, value: float) -> float:
        """A value in the range unit -> millivolts at the terminals."""
        return value / self.unit_per_mv()

    def code(self, value: float) -> int:
        """The converter code of a value in the range unit (not saturated)."""
        return round_half_away(self.to_mv(value) * CODES_PER_MV)

    def from_code(self, code: int) -> float:
        """The value in the range unit a converter code stands for."""
        return code * LSB_MV * self.unit_per_mv()


# AEM 2.3-1 (limits) and 2.3-3 (normal and extended zones), 2.3-5 (hysteresis)
RANGES: tuple[InputRange, ...] = (
    InputRange(0, "-10/+10 V", False, -10000, 10000, -11000, 11000, 100),
    InputRange(1, "-5/+5 V", False, -5000, 5000, -5500, 5500, 50),
    InputRange(2, "0/10 V", False, 0, 10000, -200, 11000, 50),
    InputRange(3, "2/10 V", False, 2000, 10000, 1840, 10800, 40),
    InputRange(4, "0/5 V", False, 0, 5000, -100, 5500, 26),  # AMB-AEM-10: the table's 26
    InputRange(5, "0/2 V", False, 0, 2000, -40, 2200, 10),
    InputRange(6, "0.4/2 V", False, 400, 2000, 368, 2160, 8),
    InputRange(7, "0/20 mA", True, 0, 20000, -400, 22000, 100),
    InputRange(8, "4/20 mA", True, 4000, 20000, 3680, 21600, 80),
)

_ALIASES = {r.name.replace(" ", "").replace("+", "").lower(): r.number for r in RANGES} | {
    "4-20ma": 8,
    "0-20ma": 7,
    "0-10v": 2,
    "2-10v": 3,
    "0-5v": 4,
    "0-2v": 5,
}


def range_by_name(text: str) -> InputRange | None:
    """'4/20mA', '0/10 V', '-10/+10V' -> the range (None if unknown)."""
    key = text.replace(" ", "").replace("+", "").lower()
    number = _ALIASES.get(key)
    return None if number is None else RANGES[number]
