"""A plant-file table -> a signal: ``{kind = "sine", offset = 5.0, amplitude = 2.0, ...}``.

Times in plant files are seconds (floats); signals take integer microseconds.  Every
mistake is a ConfigError whose message starts with ``where`` and the field, and says
what is allowed (DESIGN rule 9).  docs/signals.md describes every kind.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TypeGuard, cast

from fieldtwin.clock import seconds
from fieldtwin.errors import ConfigError
from fieldtwin.signals.analog import (
    Constant,
    Noise,
    PiecewiseLinear,
    Ramp,
    Sine,
    Square,
    Step,
    Sum,
)
from fieldtwin.signals.base import AnalogSignal, DiscreteSignal
from fieldtwin.signals.discrete import DiscreteConstant, Edges, PulseTrain, RandomEdges

Signal = AnalogSignal | DiscreteSignal

DISCRETE_TYPES = (DiscreteConstant, PulseTrain, Edges, RandomEdges)


MAX_TIME_S = 1e9  # about 31 years: times and durations of a signal stay below it


class _Fields:
    """The keys of one spec table, read once each; leftovers are reported."""

    def __init__(self, spec: Mapping[str, object], where: str, base_dir: Path | None) -> None:
        self.spec, self.where, self.base_dir = spec, where, base_dir

    def fail(self, key: str, message: str) -> ConfigError:
        return ConfigError(f"{self.where}.{key}: {message}")

    def raw(self, key: str, default: object = None) -> object:
        if key in self.spec:
            return self.spec[key]
        if default is None:
            raise self.fail(key, "missing")
        return default

    def number(self, key: str, default: float | None = None) -> float:
        value = self.raw(key, default)
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.fail(key, f"{value!r} is not a number")
        if not math.isfinite(value):
            raise self.fail(key, f"{value!r} is not a finite number")
        return float(value)

    def integer(self, key: str) -> int:
        value = self.raw(key)
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.fail(key, f"{value!r} is not a whole number")
        return value

    def boolean(self, key: str, default: bool | None = None) -> bool:
        value = self.raw(key, default)
        if not isinstance(value, bool):
            raise self.fail(key, f"{value!r} is not true or false")
        return value

    def time_us(self, key: str, default: float | None = None) -> int:
        """A time in seconds (>= 0) -> us."""
        value = self.number(key, default)
        if value < 0:
            raise self.fail(key, f"{value} s is negative (allowed >= 0)")
        if value > MAX_TIME_S:
            raise self.fail(key, f"{value} s not allowed (allowed 0..{MAX_TIME_S:g} s)")
        return seconds(value)

    def period_us(self, key: str, default: float | None = None) -> int:
        """A duration in seconds (> 0, at least 1 us) -> us."""
        value = self.number(key, default)
        if not 0 < value <= MAX_TIME_S or seconds(value) < 1:
            raise self.fail(
                key, f"{value} s is not a duration (allowed 0.000001..{MAX_TIME_S:g} s)"
            )
        return seconds(value)

    def items(self, key: str, default: list[object] | None = None) -> list[object]:
        value = self.raw(key, default)
        if not isinstance(value, list | tuple):
            raise self.fail(key, f"{value!r} is not a list")
        return list(value)

    def analog(self, key: str, value: object) -> AnalogSignal:
        return analog_from_spec(value, where=f"{self.where}.{key}", base_dir=self.base_dir)

    def fraction(self, key: str, default: float) -> float:
        value = self.number(key, default)
        if not 0.0 <= value <= 1.0:
            raise self.fail(key, f"{value} is not a fraction (allowed 0..1)")
        return value

    def check_known(self, allowed: tuple[str, ...]) -> None:
        extra = sorted(set(self.spec) - {"kind", *allowed})
        if extra:
            shown = ", ".join(("kind", *allowed))
            raise self.fail(extra[0], f"unknown field for this kind (allowed {shown})")


# --- one builder per kind ---------------------------------------------------------


def _constant(f: _Fields) -> Signal:
    value = f.raw("value")
    if isinstance(value, bool):
        return DiscreteConstant(value)
    return Constant(f.number("value"))


def _step(f: _Fields) -> Signal:
    return Step(f.number("before"), f.number("after"), f.time_us("at_s"))


def _ramp(f: _Fields) -> Signal:
    start, end = f.number("start"), f.number("end")
    return Ramp(start, end, f.time_us("t0_s", 0.0), f.time_us("duration_s"))


def _sine(f: _Fields) -> Signal:
    offset, amplitude = f.number("offset", 0.0), f.number("amplitude")
    return Sine(offset, amplitude, f.period_us("period_s"), f.number("phase_deg", 0.0))


def _square(f: _Fields) -> Signal:
    low, high, period = f.number("low"), f.number("high"), f.period_us("period_s")
    return Square(low, high, period, f.fraction("duty", 0.5))


def _is_time(value: object) -> TypeGuard[float]:
    """A number of seconds in 0..MAX_TIME_S."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return False
    return math.isfinite(value) and 0 <= value <= MAX_TIME_S


def _pair(f: _Fields, key: str, index: int, item: object) -> tuple[float, object]:
    if not isinstance(item, list | tuple) or len(item) != 2:
        raise f.fail(f"{key}[{index}]", f"{item!r} is not a pair [time_s, value]")
    t, value = item
    if not _is_time(t):
        raise f.fail(
            f"{key}[{index}]", f"time {t!r} is not a number of seconds in 0..{MAX_TIME_S:g}"
        )
    return float(t), value


def _pwl(f: _Fields) -> Signal:
    points: list[tuple[int, float]] = []
    for index, item in enumerate(f.items("points")):
        t, value = _pair(f, "points", index, item)
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise f.fail(f"points[{index}]", f"value {value!r} is not a number")
        points.append((seconds(t), float(value)))
    return PiecewiseLinear(points)


def _csv(f: _Fields) -> Signal:
    name = f.raw("file")
    if not isinstance(name, str) or not name:
        raise f.fail("file", f"{name!r} is not a file name")
    path = Path(name)
    if not path.is_absolute() and f.base_dir is not None:
        path = f.base_dir / path
    return PiecewiseLinear.from_csv(path)


def _noise(f: _Fields) -> Signal:
    base = f.analog("base", f.raw("base", {"kind": "constant", "value": 0.0}))
    sigma, seed = f.number("sigma"), f.integer("seed")
    return Noise(base, sigma, seed, f.period_us("sample_period_s", 0.001))


def _sum(f: _Fields) -> Signal:
    terms = [f.analog(f"terms[{i}]", item) for i, item in enumerate(f.items("terms"))]
    return Sum(terms)


def _pulse(f: _Fields) -> Signal:
    period, duty = f.period_us("period_s"), f.fraction("duty", 0.5)
    return PulseTrain(period, duty, f.time_us("start_s", 0.0), f.boolean("high_first", True))


def _edges(f: _Fields) -> Signal:
    initial = f.boolean("initial", False)
    if "changes" in f.spec:
        changes: list[tuple[int, bool]] = []
        for index, item in enumerate(f.items("changes")):
            t, value = _pair(f, "changes", index, item)
            if not isinstance(value, bool):
                raise f.fail(f"changes[{index}]", f"value {value!r} is not true or false")
            changes.append((seconds(t), value))
        return Edges.from_list(changes, initial=initial)
    times = []
    for index, item in enumerate(f.items("times_s")):
        if not _is_time(item):
            raise f.fail(
                f"times_s[{index}]", f"{item!r} is not a number of seconds in 0..{MAX_TIME_S:g}"
            )
        times.append(seconds(item))
    return Edges(initial, times)


def _random(f: _Fields) -> Signal:
    seed, mean = f.integer("seed"), f.period_us("mean_interval_s")
    minimum = f.period_us("min_interval_s", 0.001)
    return RandomEdges(seed, mean, minimum, f.boolean("initial", False))


_Builder = Callable[[_Fields], Signal]

# kind -> (builder, fields it takes)
KINDS: dict[str, tuple[_Builder, tuple[str, ...]]] = {
    "constant": (_constant, ("value",)),
    "step": (_step, ("before", "after", "at_s")),
    "ramp": (_ramp, ("start", "end", "t0_s", "duration_s")),
    "sine": (_sine, ("offset", "amplitude", "period_s", "phase_deg")),
    "square": (_square, ("low", "high", "period_s", "duty")),
    "pwl": (_pwl, ("points",)),
    "csv": (_csv, ("file",)),
    "noise": (_noise, ("base", "sigma", "seed", "sample_period_s")),
    "sum": (_sum, ("terms",)),
    "pulse": (_pulse, ("period_s", "duty", "start_s", "high_first")),
    "edges": (_edges, ("initial", "times_s", "changes")),
    "random": (_random, ("seed", "mean_interval_s", "min_interval_s", "initial")),
}
ANALOG_KINDS = ("constant", "step", "ramp", "sine", "square", "pwl", "csv", "noise", "sum")
DISCRETE_KINDS = ("constant", "pulse", "edges", "random")


def signal_from_spec(
    spec: Mapping[str, object], *, where: str, base_dir: Path | None = None
) -> Signal:
    """Build the signal a plant-file table describes (see docs/signals.md)."""
    if not isinstance(spec, Mapping):
        raise ConfigError(f"{where}: {spec!r} is not a table (allowed {{kind = ..., ...}})")
    kind = spec.get("kind")
    if not isinstance(kind, str) or kind not in KINDS:
        state = "missing" if kind is None else f"unknown signal kind {kind!r}"
        raise ConfigError(f"{where}.kind: {state} (allowed {', '.join(KINDS)})")
    builder, allowed = KINDS[kind]
    fields = _Fields(spec, where, base_dir)
    fields.check_known(allowed)
    if kind == "edges" and "changes" in spec and "times_s" in spec:
        raise fields.fail("changes", "give either times_s or changes, not both")
    try:
        signal = builder(fields)
    except ConfigError as exc:
        if str(exc).startswith(where):
            raise
        raise ConfigError(f"{where}: {exc}") from None
    return signal


FILE_KEYS = ("file", "path")  # keys that name a file (also any key ending _file, _path)


def file_in_spec(spec: object, where: str) -> str | None:
    """Where a signal table would read a file, or None: a ``kind = "csv"``, or a key
    that names a file, at any depth (inside a ``sum``, a ``noise`` base, a list).

    The answer is ``where`` and the path to the place, e.g. ``sig.terms[1]: kind 'csv'``;
    the doors that read no file (the control API, its console) refuse such a table
    before anything is built (docs/control.md, "Security")."""
    if isinstance(spec, Mapping):
        if str(spec.get("kind", "")).lower() == "csv":
            return f"{where}: kind 'csv'"
        for key, value in spec.items():
            name = str(key).lower()
            if name in FILE_KEYS or name.endswith(tuple(f"_{k}" for k in FILE_KEYS)):
                return f"{where}.{key}: a file name"
            found = file_in_spec(value, f"{where}.{key}")
            if found is not None:
                return found
    elif isinstance(spec, list | tuple):
        for index, value in enumerate(spec):
            found = file_in_spec(value, f"{where}[{index}]")
            if found is not None:
                return found
    return None


def is_discrete(signal: object) -> bool:
    """True for the discrete signals this package builds."""
    return isinstance(signal, DISCRETE_TYPES)


def analog_from_spec(spec: object, *, where: str, base_dir: Path | None = None) -> AnalogSignal:
    """An analog signal: a table, or a bare number for a constant."""
    if isinstance(spec, bool | int | float):
        spec = {"kind": "constant", "value": spec}
    signal = signal_from_spec(_table(spec, where), where=where, base_dir=base_dir)
    if is_discrete(signal):
        raise ConfigError(
            f"{where}: a discrete signal where an analog one is needed"
            f" (allowed kinds {', '.join(ANALOG_KINDS)}; constant takes a number)"
        )
    return signal


def discrete_from_spec(spec: object, *, where: str, base_dir: Path | None = None) -> DiscreteSignal:
    """A discrete signal: a table, or a bare true/false for a constant."""
    if isinstance(spec, bool | int | float):
        spec = {"kind": "constant", "value": spec}
    signal = signal_from_spec(_table(spec, where), where=where, base_dir=base_dir)
    if not is_discrete(signal):
        raise ConfigError(
            f"{where}: an analog signal where a discrete one is needed"
            f" (allowed kinds {', '.join(DISCRETE_KINDS)}; constant takes true or false)"
        )
    return cast(DiscreteSignal, signal)


def _table(spec: object, where: str) -> Mapping[str, object]:
    if not isinstance(spec, Mapping):
        raise ConfigError(f"{where}: {spec!r} is not a table (allowed {{kind = ..., ...}})")
    return spec
