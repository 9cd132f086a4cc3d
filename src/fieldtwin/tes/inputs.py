"""TES inputs by name, one scheme for the plant file, the console, Python and TESIS.

Digital input ``i`` is named ``"i"`` (``"0"`` .. ``"31"``), analog input ``k``
``"a<k>"`` (``"a0"`` .. ``"a7"``).  A digital value is a bool (or one of the
words of ``parse_bool``); an analog value is volts or milliamps within the
converter's span (§4.2.4 with §4.3.1: 0..10 V or 0..20 mA give 0..1023 points),
a :class:`fieldtwin.units.Quantity` or a bare number in the model's unit (volts):
a level outside the span saturates as the converter would (0 or 1023 points)
and ``level_note`` says so (docs/manual-notes.md, TES).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

from fieldtwin.errors import ConfigError
from fieldtwin.tes.models import MILLIAMPS, VOLTS, ElectricalRange, TesModel
from fieldtwin.units import Quantity, parse_quantity
from fieldtwin.units import parse_bool as _parse_bool

# §4.3.1: the converters span 0..10 V or 0..20 mA; both give the same points.
SPANS: dict[str, ElectricalRange] = {VOLTS.unit: VOLTS, MILLIAMPS.unit: MILLIAMPS}


@dataclass(frozen=True, slots=True)
class InputRef:
    """One input of a model: analog channel ``index`` or digital input ``index``."""

    analog: bool
    index: int

    @property
    def name(self) -> str:
        return f"a{self.index}" if self.analog else str(self.index)


@functools.cache
def input_names(model: TesModel) -> Mapping[str, str]:
    """name -> description of every input ``model`` has."""
    names = {str(i): f"digital input {i} (on/off)" for i in range(model.digital_inputs)}
    span = model.analog_range.describe()
    for k in model.analog_inputs:
        names[f"a{k}"] = f"analog input {k} ({span})"
    return MappingProxyType(names)


def _allowed(model: TesModel) -> str:
    parts = []
    if model.digital_inputs:
        parts.append(f"0..{model.digital_inputs - 1} digital")
    if model.analog_inputs:
        parts.append(", ".join(f"a{k}" for k in model.analog_inputs) + " analog")
    return "; ".join(parts) or "none"


def input_ref(model: TesModel, name: str | int) -> InputRef:
    """``"3"`` / ``3`` -> digital input 3, ``"a2"`` -> analog input 2; ConfigError otherwise."""
    text = str(name).strip().lower()
    analog = text.startswith("a")
    number = text[1:] if analog else text
    if not number.isdigit():
        raise ConfigError(f"{model.name}: no input {name!r} (allowed: {_allowed(model)})")
    ref = InputRef(analog, int(number))
    if ref.name in input_names(model):
        return ref
    if analog:
        allowed = ", ".join(map(str, model.analog_inputs)) or "none"
        raise ConfigError(f"{model.name}: no analog input {ref.index} (allowed: {allowed})")
    last = model.digital_inputs - 1
    allowed = f"0..{last}" if last >= 0 else "none"
    raise ConfigError(f"{model.name}: no digital input {ref.index} (allowed {allowed})")


def parse_bool(text: str, what: str) -> bool:
    """on/off, 1/0, true/false, yes/no (any case); ConfigError naming the token otherwise."""
    return _parse_bool(text, what)


def analog_level(model: TesModel, k: int, value: float | Quantity) -> float:
    """A level in the model's unit (volts): a bare number as it is, volts or milliamps scaled.

    §4.3.1 gives both spans of a TES converter, 0..10 V and 0..20 mA: ``12mA`` is
    60 % of the span, as ``6V`` is (docs/manual-notes.md, TES units).
    """
    found = parse_quantity(value, tuple(SPANS), f"{model.name} analog input a{k}")
    if not found.unit or found.unit == model.analog_range.unit:
        return found.value
    return found.value / SPANS[found.unit].full_scale * model.analog_range.full_scale


def level_note(model: TesModel, k: int, level: float) -> str | None:
    """§4.2.4 the converter saturates: a note when ``level`` is beyond its span, else None.

    A level that is not a finite number is refused (ConfigError).
    """
    span = model.analog_range
    if isinstance(level, bool) or not isinstance(level, int | float):
        raise ConfigError(f"{model.name} analog input a{k}: {level!r} is not a number")
    if not math.isfinite(level):
        raise ConfigError(f"{model.name} analog input a{k}: {level!r} is not a finite number")
    if 0.0 <= level <= span.full_scale:
        return None
    points = 0 if level < 0 else 1023
    return (
        f"{model.name} analog input a{k}: {level:g} {span.unit} is outside the converter's"
        f" {span.describe()}: saturated, it reads as {points} points (§4.2.4)"
    )
