"""One value language: quantities with units, on/off words, durations, hex words.

Every device, the plant file, the console and the control API read a value
through this module, so that ``"2.5V"`` means the same everywhere:

* electrical values: ``"2.5V"``, ``"2500mV"``, ``"12mA"``, ``"12000uA"`` (``µA``
  too) give a :class:`Quantity` in volts (``V``) or milliamps (``mA``); a bare
  number (``"3"``, ``3.0``) is a quantity without unit (``""``): the device says
  which unit its bare numbers are in (docs/architecture.md);
* durations: ``"250ms"``, ``"1.5s"``, ``"2min"``, ``"500us"`` (a bare number is seconds);
* on/off: ``1``/``0``, ``on``/``off``, ``true``/``false``, ``yes``/``no`` (any case);
* words: ``H'00A0'`` (:func:`fieldtwin.words.parse_word`).

Every parser raises ConfigError naming the token and what is allowed.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from fieldtwin.errors import ConfigError
from fieldtwin.words import parse_word

VOLTS = "V"
MILLIAMPS = "mA"
SECONDS = "s"
NONE = ""  # a bare number: in the unit the device gives it

TRUE_WORDS = ("on", "1", "true", "yes")
FALSE_WORDS = ("off", "0", "false", "no")

# suffix (lower case) -> (unit, factor to that unit)
_SUFFIXES: dict[str, tuple[str, float]] = {
    "v": (VOLTS, 1.0),
    "mv": (VOLTS, 1e-3),
    "ma": (MILLIAMPS, 1.0),
    "ua": (MILLIAMPS, 1e-3),
    "µa": (MILLIAMPS, 1e-3),
    "s": (SECONDS, 1.0),
    "ms": (SECONDS, 1e-3),
    "us": (SECONDS, 1e-6),
    "µs": (SECONDS, 1e-6),
    "min": (SECONDS, 60.0),
    "h": (SECONDS, 3600.0),
}
_EXAMPLES = {VOLTS: "2.5V, 2500mV", MILLIAMPS: "12mA, 12000uA", SECONDS: "1.5s, 250ms"}
_TEXT = re.compile(r"^([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([a-zµ]*)$", re.IGNORECASE)


@dataclass(frozen=True, slots=True)
class Quantity:
    """A finite number and its unit: ``Quantity(2.5, "V")``; unit ``""`` for a bare number."""

    value: float
    unit: str = NONE

    def __str__(self) -> str:
        return f"{self.value:g}{self.unit}" if self.unit else f"{self.value:g}"


def _examples(allowed: tuple[str, ...]) -> str:
    return ", ".join(_EXAMPLES[u] for u in allowed if u in _EXAMPLES)


def parse_quantity(
    value: object, allowed: tuple[str, ...] = (VOLTS, MILLIAMPS), what: str = "value"
) -> Quantity:
    """``"2.5V"`` -> Quantity(2.5, "V"); a number or a bare ``"3"`` -> Quantity(3.0, "").

    ``allowed`` are the units the caller takes (a bare number is always taken);
    a Quantity is checked against them.  ConfigError naming ``what``, the token
    and the allowed units otherwise.
    """
    if isinstance(value, Quantity):
        found = value
    elif isinstance(value, bool):
        raise ConfigError(f"{what}: {value!r} is not a number (allowed e.g. {_examples(allowed)})")
    elif isinstance(value, int | float):
        found = Quantity(float(value))
    elif isinstance(value, str):
        found = _parse_text(value, allowed, what)
    else:
        raise ConfigError(f"{what}: {value!r} is not a number (allowed e.g. {_examples(allowed)})")
    if not math.isfinite(found.value):
        raise ConfigError(f"{what}: {value!r} is not a finite number")
    if found.unit and found.unit not in allowed:
        raise ConfigError(
            f"{what}: {value!s} is in {found.unit}, not allowed here"
            f" (allowed units: {', '.join(allowed) or 'none'}; e.g. {_examples(allowed)})"
        )
    return found


def _parse_text(text: str, allowed: tuple[str, ...], what: str) -> Quantity:
    match = _TEXT.match(text.strip())
    suffix = (match.group(2) or "").lower() if match else ""
    if match is None or (suffix and suffix not in _SUFFIXES):
        raise ConfigError(
            f"{what}: {text!r} not allowed (allowed e.g. {_examples(allowed)}, or a bare number)"
        )
    number = float(match.group(1))
    if not suffix:
        return Quantity(number)
    unit, factor = _SUFFIXES[suffix]
    return Quantity(number * factor, unit)


def parse_bool(value: object, what: str = "value") -> bool:
    """True/False, 1/0, or on/off, 1/0, true/false, yes/no (any case); ConfigError otherwise."""
    if isinstance(value, bool):
        return value
    if isinstance(value, int | float) and value in (0, 1):
        return bool(value)
    if isinstance(value, str):
        word = value.strip().lower()
        if word in TRUE_WORDS or word == "1.0":
            return True
        if word in FALSE_WORDS or word == "0.0":
            return False
    raise ConfigError(
        f"{what}: {value!r} is not on or off (allowed: {', '.join(TRUE_WORDS + FALSE_WORDS)})"
    )


def parse_duration(value: object, what: str = "duration") -> float:
    """``"11"``, ``"250ms"``, ``"2min"``, ``"1.5s"``, or a number -> seconds (>= 0)."""
    try:
        found = parse_quantity(value, (SECONDS,), what)
    except ConfigError:
        raise ConfigError(f"{value!r} is not a duration (e.g. 11, 1.5s, 250ms, 2min)") from None
    if found.value < 0:
        raise ConfigError(f"{value!r}: a duration cannot be negative")
    return found.value


def parse_hex(token: str) -> int:
    """``H'00A0'``, ``0x00A0``, ``160`` or ``-5`` -> a word 0..65535 (fieldtwin.words)."""
    return parse_word(token)


__all__ = [
    "FALSE_WORDS",
    "MILLIAMPS",
    "NONE",
    "SECONDS",
    "TRUE_WORDS",
    "VOLTS",
    "Quantity",
    "parse_bool",
    "parse_duration",
    "parse_hex",
    "parse_quantity",
]
