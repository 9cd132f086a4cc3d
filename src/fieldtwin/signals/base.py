"""What every input signal offers, and the seeded hash that makes random ones repeatable.

A signal gives its value at a simulated time ``t`` (integer microseconds) and says
when it next changes, so that a device can schedule the next edge instead of
polling (DESIGN rule 3).  Random signals derive each draw from a hash of
(seed, index): the same seed gives the same values whatever order they are asked in.
"""

from __future__ import annotations

import hashlib
import math
import struct
from typing import Protocol, runtime_checkable

from fieldtwin.errors import ConfigError


@runtime_checkable
class AnalogSignal(Protocol):
    """A float in the signal's own unit (the device decides: volts, milliamps...)."""

    def value_at(self, t: int) -> float:
        """The value at simulated time ``t`` (us)."""
        ...

    def next_change(self, t: int) -> int | None:
        """The next breakpoint after ``t`` (a jump, or where a ramp starts or ends).

        None when no breakpoint lies ahead: the value is constant from now on, or it
        varies smoothly for ever (a sine) and a device samples it at its own times.
        """
        ...


@runtime_checkable
class DiscreteSignal(Protocol):
    """A bool: a discrete input (contact closed = True)."""

    def value_at(self, t: int) -> bool:
        """The value at simulated time ``t`` (us)."""
        ...

    def next_change(self, t: int) -> int | None:
        """The first time > ``t`` at which the value differs from ``value_at(t)``.

        None when the value never changes again.
        """
        ...


@runtime_checkable
class SteppedSignal(Protocol):
    """A discrete signal that answers ``value_at`` and ``next_change`` in one call."""

    def value_and_next(self, t: int) -> tuple[bool, int | None]:
        """``(value_at(t), next_change(t))``, the same answers, one search."""
        ...


# --- argument checks (ConfigError naming the argument) -----------------------------


def check_finite(name: str, value: float) -> None:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ConfigError(f"{name} must be a finite number, got {value!r}")


def check_period(name: str, value: int) -> None:
    if isinstance(value, bool) or not isinstance(value, int) or value <= 0:
        raise ConfigError(f"{name} must be a whole number of us > 0, got {value!r}")


def check_fraction(name: str, value: float) -> None:
    check_finite(name, value)
    if not 0.0 <= value <= 1.0:
        raise ConfigError(f"{name} must be within 0..1, got {value!r}")


# --- seeded draws ----------------------------------------------------------------------

_TWO_64 = float(1 << 64)


def _digest(seed: int, stream: str, index: int) -> bytes:
    key = f"{seed}:{stream}:{index}".encode()
    return hashlib.blake2b(key, digest_size=16).digest()


def uniform(seed: int, stream: str, index: int) -> float:
    """A uniform draw in (0, 1), a pure function of (seed, stream, index)."""
    raw = int.from_bytes(_digest(seed, stream, index)[:8], "little")
    return (raw + 0.5) / _TWO_64


_LOW_64 = struct.Struct("<Q").unpack_from  # the first 8 bytes, little-endian


class UniformStream:
    """``uniform(seed, stream, index)`` for one (seed, stream) and whole ``index``, faster.

    The hash of the key's prefix is computed once and copied for each draw; the
    digest of prefix + index is the same bytes as :func:`_digest`'s, so every draw is
    bit-identical to :func:`uniform`'s.
    """

    __slots__ = ("_prefix",)

    def __init__(self, seed: int, stream: str) -> None:
        self._prefix = hashlib.blake2b(f"{seed}:{stream}:".encode(), digest_size=16)

    def __call__(self, index: int) -> float:
        h = self._prefix.copy()
        h.update(str(index).encode())  # f"{index}", as _digest writes it
        raw: int = _LOW_64(h.digest())[0]
        return (raw + 0.5) / _TWO_64


def gauss(seed: int, stream: str, index: int) -> float:
    """A standard normal draw (Box-Muller), a pure function of (seed, stream, index)."""
    digest = _digest(seed, stream, index)
    u1 = (int.from_bytes(digest[:8], "little") + 0.5) / _TWO_64
    u2 = int.from_bytes(digest[8:], "little") / _TWO_64
    return math.sqrt(-2.0 * math.log(u1)) * math.cos(2.0 * math.pi * u2)
