"""An AEM 811 channel's value as the plant file, the console and the control API give it.

``"2.5V"``, ``"2500mV"``, ``"12mA"``, ``"12000uA"`` (fieldtwin.units), ``"open"``,
or a bare number in the unit of the channel's range (milliamps on 0/20 and
4/20 mA, volts otherwise; AEM 6.3-4).  The core takes the typed value.
"""

from __future__ import annotations

from fieldtwin.errors import ConfigError
from fieldtwin.tsx.aem811.module import Aem811
from fieldtwin.units import MILLIAMPS, VOLTS, parse_quantity

OPEN_WORDS = ("open", "open_circuit", "cut")
ALLOWED = (
    "allowed e.g. 2.5V, 2500mV, 12mA, 12000uA, open, or a number in the unit of the channel's range"
)


def set_value(aem: Aem811, channel: int, value: object) -> None:
    """Put ``value`` on ``channel``; ConfigError naming the token and what is allowed."""
    if isinstance(value, bool):
        raise ConfigError(f"input {channel}: {value!r} ({ALLOWED})")
    if isinstance(value, str) and value.strip().lower() in OPEN_WORDS:
        aem.set_input(channel, open_circuit=True)
        return
    try:
        found = parse_quantity(value, (VOLTS, MILLIAMPS), f"input {channel}")
    except ConfigError:
        raise ConfigError(f"input value {value!r} not allowed ({ALLOWED})") from None
    if found.unit == VOLTS:
        aem.set_input(channel, volts=found.value)
    elif found.unit == MILLIAMPS:
        aem.set_input(channel, milliamps=found.value)
    else:
        aem.set_level(channel, found.value)
