"""The runner's pacing parts: speed bounds, a run's pace, the speed reached, modes.

Speed bounds (docs/control.md, "The clock"): a speed factor is a number from
MIN_SPEED to MAX_SPEED, or None (``max``: as fast as the plant runs).  Below
MIN_SPEED simulated time would all but stand still (a 10 ms master task once
every few hours of wall time); MAX_SPEED is the most the runner is asked to
keep: past what a plant can do it runs as fast as it can and says so (the
speed reached), and it stays reachable whatever the factor, because catch-up
work is cut into slices (CATCH_UP_SLICE_S, docs/decisions.md "Bounded catch-up
and runner modes").
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

from fieldtwin.clock import Handle
from fieldtwin.errors import ConfigError

MIN_SPEED = 1e-3  # the slowest speed factor: 1 simulated second per 1000 wall seconds
MAX_SPEED = 1e5  # the fastest speed factor asked for; "max" has no pace at all
# The most wall time one paced cycle spends catching the clock up before it serves
# commands, descriptors and the stop flag again (issue 20 R1).
CATCH_UP_SLICE_S = 0.05
# How far (wall seconds) the clock may lag its pace before the pace is moved to where
# the clock stands: the plant does not keep the speed, it runs as fast as it can.
MAX_LAG_S = 0.5
REACHED_WINDOW_S = 2.0  # the speed reached is measured over this much wall time
REACHED_SAMPLE_S = 0.1  # one sample of (wall, simulated) time at most this often


def speed_range() -> str:
    return f"a factor from {MIN_SPEED:g} to {MAX_SPEED:g}, or max"


def check_speed(speed: float | None, where: str = "speed") -> float | None:
    """``speed`` if it is None (max) or a factor within the bounds; else a ConfigError."""
    if speed is None:
        return None
    if isinstance(speed, bool) or not MIN_SPEED <= speed <= MAX_SPEED:
        raise ConfigError(f"{where}={speed!r} not allowed (allowed: {speed_range()})")
    return float(speed)


@dataclass(slots=True)
class Pace:
    """The wall <-> simulated time mapping of one run: (wall0, sim0) at ``speed``."""

    wall0: float
    sim0: int
    speed: float

    def sim_at(self, wall: float) -> int:
        return self.sim0 + round((wall - self.wall0) * self.speed * 1_000_000)

    def wall_at(self, sim: int) -> float:
        return self.wall0 + (sim - self.sim0) / (self.speed * 1_000_000)


class SpeedMeter:
    """Simulated seconds per wall second over the last REACHED_WINDOW_S (a sliding window)."""

    def __init__(self) -> None:
        self._samples: deque[tuple[float, int]] = deque()

    def reset(self) -> None:
        """Time held, or a new speed: measure afresh."""
        self._samples.clear()

    def sample(self, wall: float, sim: int) -> None:
        samples = self._samples
        if samples and wall - samples[-1][0] < REACHED_SAMPLE_S:
            return
        samples.append((wall, sim))
        while wall - samples[0][0] > REACHED_WINDOW_S:
            samples.popleft()

    @property
    def reached(self) -> float | None:
        """None until two samples (REACHED_SAMPLE_S apart) are there."""
        if len(self._samples) < 2:
            return None
        (w0, s0), (w1, s1) = self._samples[0], self._samples[-1]
        return (s1 - s0) / 1_000_000 / (w1 - w0)


@dataclass(slots=True)
class Mode:
    """A run of simulated time the runner does between its cycles (issue 20 item 5):
    ``name`` ("step", "run-until", "power-break") until simulated time ``until``, paused
    or not; ``on_end(now, cut)`` when it ends (cut: replaced, paused or ended early)."""

    name: str
    until: int
    on_end: Callable[[int, bool], None] | None
    handle: Handle | None = None  # the clock event at ``until`` that ends it


__all__ = [
    "CATCH_UP_SLICE_S",
    "MAX_LAG_S",
    "MAX_SPEED",
    "MIN_SPEED",
    "REACHED_WINDOW_S",
    "Mode",
    "Pace",
    "SpeedMeter",
    "check_speed",
    "speed_range",
]
