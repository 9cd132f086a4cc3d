"""What is wired to a channel: a voltage, a current, an open circuit, or a signal.

AEM 6.3-4: a current input is read as the voltage across the 100 ohm resistor
of the terminal block, so a current of I mA is I x 100 mV at the terminals.
A signal given without a unit is read in the unit of the channel's range
(milliamps on 0/20 and 4/20 mA, volts otherwise).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from fieldtwin.errors import ConfigError
from fieldtwin.signals.base import AnalogSignal
from fieldtwin.tsx.aem811.ranges import SHUNT_OHMS

UNITS = ("V", "mA", "auto")


@dataclass(frozen=True, slots=True)
class ChannelInput:
    """A channel's electrical input; ``open`` wins over the rest."""

    unit: str = "V"  # "V", "mA" or "auto" (the unit of the channel's range)
    value: float = 0.0
    signal: AnalogSignal | None = None
    open: bool = False

    def millivolts(self, t: int, current_range: bool) -> float | None:
        """Terminal millivolts at time ``t`` (None: open circuit)."""
        if self.open:
            return None
        value = self.signal.value_at(t) if self.signal is not None else self.value
        milliamps = self.unit == "mA" or (self.unit == "auto" and current_range)
        return value * SHUNT_OHMS if milliamps else value * 1000.0

    def next_change(self, t: int) -> int | None:
        return None if self.signal is None or self.open else self.signal.next_change(t)


def electrical(
    *, volts: float | None = None, milliamps: float | None = None, open_circuit: bool = False
) -> ChannelInput:
    """The input ``set_input`` takes: exactly one of volts, milliamps, open_circuit."""
    given = [volts is not None, milliamps is not None, bool(open_circuit)]
    if sum(given) != 1:
        raise ConfigError("set_input takes exactly one of volts=, milliamps=, open_circuit=True")
    if open_circuit:
        return ChannelInput(open=True)
    value = volts if volts is not None else milliamps
    assert value is not None
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ConfigError(f"input value {value!r} is not a finite number")
    return ChannelInput("V" if volts is not None else "mA", float(value))
