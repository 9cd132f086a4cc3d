"""A TES input's value as the plant file, the console and the control API give it.

Digital: ``1``/``0``, ``on``/``off``, ``true``/``false`` (fieldtwin.units).  Analog:
``"3V"``, ``"2500mV"``, ``"12mA"`` or a bare number in volts, the unit of every
TES analog input (docs/tes.md, "Units"); the core scales milliamps onto its
0..20 mA span (§4.3.1) and saturates beyond the span with a note (§4.2.4).
"""

from __future__ import annotations

from fieldtwin.errors import ConfigError
from fieldtwin.units import MILLIAMPS, VOLTS, Quantity, parse_bool, parse_quantity


def contact_value(kind: str, i: int, value: object) -> bool:
    """A digital input's level; ConfigError naming the input and the allowed words."""
    try:
        return parse_bool(value, f"{kind} input {i}")
    except ConfigError:
        raise ConfigError(
            f"{kind} input {i}: {value!r} not allowed (allowed 1/0, on/off, true/false)"
        ) from None


def analog_value(kind: str, k: int, value: object) -> Quantity:
    """An analog input's value: volts, milliamps, or a bare number (volts)."""
    if isinstance(value, bool):
        raise ConfigError(f"{kind} input a{k}: {value!r} is not a number")
    try:
        return parse_quantity(value, (VOLTS, MILLIAMPS), f"{kind} input a{k}")
    except ConfigError as exc:
        if isinstance(value, str) and not any(c.isdigit() for c in value):
            raise ConfigError(
                f"{kind} input a{k}: {value!r} is not a number (allowed e.g. 3V, 2500mV, 12mA,"
                " or a bare number in volts)"
            ) from None
        raise exc from None
