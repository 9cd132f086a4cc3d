"""Detection of oscillating inputs (DEM 2.3-3, 3.2-1): a hysteresis on transition counts.

An input becomes oscillating when it changes more than N-MAX times within a sliding
T-MAX window; it is normal again once it changes fewer than N-MIN times within the
last T-MIN window (AMB-DEM-11).  Windows are half-open: a transition exactly T ago
has left the window.  The detector is pure: it answers with the next time at which
the return to normal must be checked, and the module schedules it.
"""

from __future__ import annotations

import enum
from collections import deque
from dataclasses import dataclass

from fieldtwin.clock import S


class OscState(enum.Enum):
    NORMAL = "normal"
    OSCILLATING = "oscillating"


@dataclass(frozen=True, slots=True)
class Thresholds:
    t_max_us: int
    n_max: int
    t_min_us: int
    n_min: int

    @staticmethod
    def from_config(t_max_s: int, n_max: int, t_min_s: int, n_min: int) -> Thresholds:
        return Thresholds(t_max_s * S, n_max, t_min_s * S, n_min)


class Detector:
    """One channel's transition history and oscillation state."""

    __slots__ = ("_times", "declared_at", "state", "thresholds")

    def __init__(self, thresholds: Thresholds) -> None:
        self.thresholds = thresholds
        self._times: deque[int] = deque(maxlen=max(thresholds.n_max + 1, thresholds.n_min))
        self.state = OscState.NORMAL
        self.declared_at = 0

    @property
    def oscillating(self) -> bool:
        return self.state is OscState.OSCILLATING

    def transition(self, t: int) -> bool:
        """Count a transition at ``t``; True when it makes the input oscillating."""
        self._times.append(t)
        th = self.thresholds
        if self.state is OscState.NORMAL and self._count(t, th.t_max_us) > th.n_max:
            self.state = OscState.OSCILLATING  # DEM 3.2-1 "changes more than N-MAX times"
            self.declared_at = t
            return True
        return False

    def _count(self, t: int, window: int) -> int:
        return sum(1 for x in self._times if x > t - window)

    def next_check(self) -> int | None:
        """When an oscillating input can first be normal again (None if normal)."""
        if self.state is OscState.NORMAL:
            return None
        th = self.thresholds
        times = self._times
        # fewer than N-MIN in (t - T-MIN, t] <=> the N-MIN-th latest is <= t - T-MIN
        at = times[-th.n_min] + th.t_min_us if len(times) >= th.n_min else 0
        return max(at, self.declared_at + 1)

    def check(self, t: int) -> bool:
        """True when the input returns to normal at ``t`` (DEM 3.2-1 "less than N-MIN")."""
        if self.state is OscState.OSCILLATING and self._count(t, self.thresholds.t_min_us) < (
            self.thresholds.n_min
        ):
            self.state = OscState.NORMAL
            return True
        return False
