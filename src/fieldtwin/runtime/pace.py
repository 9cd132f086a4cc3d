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

from fieldtwin.clock import Handle, SimClock
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
MODE_LAST = 1 << 30  # a mode's end runs after every other event of its instant


def speed_range() -> str:
    return f"a factor from {MIN_SPEED:g} to {MAX_SPEED:g}, or max"


def check_speed(speed: float | None, where: str = "speed") -> float | None:
    """``speed`` if it is None (max) or a factor within the bounds; else a ConfigError."""
    if speed is None:
        return None
    if isinstance(speed, bool) or not MIN_SPEED <= speed <= MAX_SPEED:
        raise ConfigError(f"{where}={speed!r} not allowed (allowed: {speed_range()})")
    return float(speed)


def check_not_past(t_us: int, now: int) -> None:
    """A run until ``t_us`` is possible from ``now``; else a ConfigError (time never goes back)."""
    if t_us < now:
        raise ConfigError(
            f"cannot run until t = {t_us / 1e6:g} s: simulated time is already"
            f" {now / 1e6:.6f} s and never goes back"
        )


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


class Tempo:
    """The pace of every run in progress (outermost first; a command's run nests in the
    run that took it), the speed reached, and whether the plant keeps its speed."""

    def __init__(self, report: Callable[[str], None]) -> None:
        self.meter = SpeedMeter()
        self._report = report
        self._paces: list[Pace] = []
        self.lagged_at = float("-inf")  # wall time the pace was last moved (speed not kept)
        self._lag_told = False

    def begin(self, wall: float, sim: int, factor: float) -> Pace:
        """A run starts at (wall, sim): its pace."""
        pace = Pace(wall, sim, factor)
        self._paces.append(pace)
        return pace

    def end(self) -> None:
        """The innermost run has ended."""
        self._paces.pop()

    def repace(self, wall: float, sim: int, factor: float) -> None:
        """Every run's pace starts again from (wall, sim): no jump in simulated time."""
        for pace in self._paces:
            pace.wall0, pace.sim0, pace.speed = wall, sim, factor

    def lagging(self, wall: float) -> bool:
        """The pace was moved less than REACHED_WINDOW_S ago (the speed is not kept)."""
        return wall - self.lagged_at < REACHED_WINDOW_S

    def kept(self, woke: float, sim: int, pace: Pace) -> bool:
        """After a paced cycle: sample the speed; if the clock lags ``pace`` by more than
        MAX_LAG_S, move every pace to (woke, sim), say so the first time, return False."""
        self.meter.sample(woke, sim)
        if woke - pace.wall_at(sim) <= MAX_LAG_S:
            return True
        self.repace(woke, sim, pace.speed)
        self.lagged_at = woke
        if not self._lag_told:
            self._lag_told = True
            self._report(
                f"the plant cannot keep speed x{pace.speed:g}: it runs as fast as it can"
                " (the speed reached is in GET /clock and the status line)"
            )
        return False


@dataclass(slots=True)
class Mode:
    """A run of simulated time the runner does between its cycles (issue 20 item 5):
    ``name`` ("step", "run-until", "power-break") until simulated time ``until``, paused
    or not; ``on_end(now, cut)`` when it ends (cut: replaced, paused or ended early)."""

    name: str
    until: int
    on_end: Callable[[int, bool], None] | None
    handle: Handle | None = None  # the clock event at ``until`` that ends it


class Modes:
    """The mode in progress, one at most (issue 20 item 5): started, ended by its clock
    event (after the others of its instant) or cut; ``on_due()`` when it ends by itself."""

    def __init__(self, clock: SimClock, on_due: Callable[[], None]) -> None:
        self.clock = clock
        self.current: Mode | None = None
        self._on_due = on_due  # told when a mode ends by itself

    def start(self, name: str, until: int, on_end: Callable[[int, bool], None] | None) -> Mode:
        """The mode in progress, if any, is cut first."""
        self.cut()
        mode = Mode(name, until, on_end)
        mode.handle = self.clock.schedule(until, lambda now: self._due(mode), MODE_LAST)
        self.current = mode
        return mode

    def cut(self) -> None:
        """End the mode in progress now (cut); nothing if none."""
        mode = self.current
        if mode is None:
            return
        self.current = None
        if mode.handle is not None:
            mode.handle.cancel()
        if mode.on_end is not None:
            mode.on_end(self.clock.now, True)

    def _due(self, mode: Mode) -> None:
        if self.current is mode:
            self.current = None
            self._on_due()
            if mode.on_end is not None:
                mode.on_end(self.clock.now, False)


__all__ = [
    "CATCH_UP_SLICE_S",
    "MAX_LAG_S",
    "MAX_SPEED",
    "MIN_SPEED",
    "MODE_LAST",
    "REACHED_WINDOW_S",
    "Mode",
    "Modes",
    "Pace",
    "SpeedMeter",
    "Tempo",
    "check_not_past",
    "check_speed",
    "speed_range",
]
