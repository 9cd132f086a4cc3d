"""Time helpers and assertions for tests of a plant, a PLC, a TES or a running plant.

Every failure is an ``AssertionError`` whose message names the object, what was
expected, what was found and the simulated time (docs/testing.md)::

    advance_to(plant, 15.0)
    run_until(plant, lambda: plant.plc.read("W0") > 500, within=30, show=["W0", "IW5,0"])
    assert_object(plant, "IW5,0", 500, tolerance=10)
    assert_leds(plant, {"OK": "on", "ERR": "off"}, device="5")
"""

from __future__ import annotations

import inspect
import math
import re
from collections.abc import Callable, Mapping, Sequence
from typing import TypeVar

from fieldtwin.errors import ConfigError
from fieldtwin.testing.targets import target_of, time_text
from fieldtwin.words import format_hex

T = TypeVar("T")
MAX_WITHIN_S = 366 * 24 * 3600.0  # a bound is a bound: at most a simulated year


class NotWithin(AssertionError):
    """``run_until`` reached its bound: the simulated time and the last values say where."""

    def __init__(self, message: str, t_s: float, last: object, values: Mapping[str, object]):
        super().__init__(message)
        self.t_s = t_s
        self.last = last
        self.values = dict(values)


def _value_text(value: object) -> str:
    if isinstance(value, bool) or not isinstance(value, int):
        return repr(value)
    return f"{value} ({format_hex(value)})" if value > 1 else str(value)


def _predicate_text(predicate: Callable[[], object]) -> str:
    """The lambda as written in the test, or the function's name."""
    name = getattr(predicate, "__qualname__", repr(predicate))
    if getattr(predicate, "__name__", "") != "<lambda>":
        return name
    try:
        source = inspect.getsource(predicate)
    except (OSError, TypeError):
        return name
    found = re.search(r"lambda\b.*", " ".join(source.split()))
    if found is None:
        return name
    text = found.group(0)
    depth = 0  # cut at the comma or parenthesis that ends the lambda's expression
    for i, char in enumerate(text):
        if char in "([{":
            depth += 1
        elif char in ")]}":
            if depth == 0:
                return text[:i].strip()
            depth -= 1
        elif char == "," and depth == 0:
            return text[:i].strip()
    return text.strip()


def _shown(target: object, names: Sequence[str]) -> dict[str, object]:
    view = target_of(target)
    values: dict[str, object] = {}
    for name in names:
        try:
            values[name] = view.value(name)
        except ConfigError as exc:  # a name the test got wrong is shown, not hidden
            values[name] = f"<{exc}>"
    return values


def advance_to(target: object, t_s: float) -> None:
    """Run ``target``'s simulated time up to ``t_s`` seconds (never back: AssertionError)."""
    __tracebackhide__ = True  # pytest shows the test's line, not this one
    view = target_of(target)
    try:
        view.advance_to(t_s)
    except ConfigError as exc:
        raise AssertionError(f"advance_to({t_s:g}) on {view.label}: {exc}") from None


def run_until(
    target: object,
    predicate: Callable[[], T],
    *,
    within: float,
    show: Sequence[str] | None = None,
    step: float | None = None,
) -> T:
    """Run simulated time until ``predicate()`` is true, at most ``within`` simulated
    seconds; returns the predicate's (true) value.

    In-process targets check the predicate after every instant at which something
    happens (or every ``step`` seconds); a running plant is polled while it runs.
    At the bound: :class:`NotWithin`, with the simulated time, the predicate's last
    value and the last values of the objects in ``show`` (default: the PLC's watch
    list, W0..W7 unless the plant file sets ``watch``)."""
    if not (isinstance(within, int | float) and 0 <= within <= MAX_WITHIN_S):
        raise ValueError(f"within={within!r}: a bound in simulated seconds, 0..{MAX_WITHIN_S:g}")
    if step is not None and not (math.isfinite(step) and step > 0):
        raise ValueError(f"step={step!r}: a positive number of simulated seconds")
    __tracebackhide__ = True
    view = target_of(target)
    start = view.now_s()
    try:
        done, last = view.run_until(predicate, float(within), step)
    except ConfigError as exc:
        raise AssertionError(f"run_until on {view.label}: {exc}") from None
    if done:
        return last  # type: ignore[return-value]
    names = list(show) if show is not None else view.default_show()
    values = _shown(target, names)
    now = view.now_s()
    lines = [
        f"run_until on {view.label}: {_predicate_text(predicate)}"
        f" not true within {within:g} s (from {time_text(start)} to {time_text(now)})",
        f"  last value of the predicate: {last!r}",
    ]
    if values:
        shown = ", ".join(f"{k} = {_value_text(v)}" for k, v in values.items())
        lines.append(f"  at {time_text(now)}: {shown}")
    raise NotWithin("\n".join(lines), now, last, values)


def _fail(what: str, label: str, expected: str, actual: str, t_s: float) -> AssertionError:
    return AssertionError(
        f"{what} of {label}: expected {expected}, actual {actual} at {time_text(t_s)}"
    )


def assert_object(
    target: object,
    name: str,
    expected: int,
    *,
    tolerance: int = 0,
    signed: bool = False,
) -> int:
    """``name`` (a PLC object ``IW5,0``, a TES word ``0x005``, or ``DEVICE:OBJECT``
    like ``tes1:0x005``) reads ``expected`` (within ``tolerance``), without side effect;
    ``signed``: compare the word as -32768..32767.  Returns the value read."""
    __tracebackhide__ = True
    view = target_of(target)
    try:
        value = view.value(name)
    except ConfigError as exc:
        raise AssertionError(f"{name} of {view.label}: {exc}") from None
    if signed:
        value = value - 0x10000 if value >= 0x8000 else value
    if abs(value - expected) > tolerance:
        want = _value_text(expected) + (f" ± {tolerance}" if tolerance else "")
        raise _fail(name, view.label, want, _value_text(value), view.now_s())
    return value


def assert_leds(target: object, expected: Mapping[str, str], *, device: str | None = None) -> None:
    """The LEDs named in ``expected`` ("on", "off", "blink"...) are in that state; a
    plant, PLC or running plant needs the ``device`` ("5", "tes1")."""
    __tracebackhide__ = True
    view = target_of(target)
    try:
        label, leds = view.leds(device)
    except ConfigError as exc:
        raise AssertionError(f"LEDs of {device or view.label}: {exc}") from None
    for led, want in expected.items():
        if led not in leds:
            raise AssertionError(
                f"{label} of {view.label} has no LED {led!r} (has: {', '.join(leds)})"
            )
        if leds[led] != want:
            everything = " ".join(f"{k}={v}" for k, v in leds.items())
            raise _fail(
                f"LED {led} of {label}",
                view.label,
                repr(want),
                f"{leds[led]!r} ({everything})",
                view.now_s(),
            )


def assert_state(target: object, expected: str, *, device: str | None = None) -> None:
    """The device is in ``expected`` state ("operational", "self-test", "on"...)."""
    __tracebackhide__ = True
    view = target_of(target)
    try:
        label, state = view.state(device)
    except ConfigError as exc:
        raise AssertionError(f"state of {device or view.label}: {exc}") from None
    if state != expected:
        raise _fail(f"state of {label}", view.label, repr(expected), repr(state), view.now_s())
