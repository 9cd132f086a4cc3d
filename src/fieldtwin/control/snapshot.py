"""The snapshot the simulation publishes for the reads that change nothing
(docs/control.md, "Reads from a snapshot").

``GET /clock``, a device's status and LEDs, the dashboard's state and an object's
``peek`` are answered from the last value the simulation's thread produced for
that read, without a hop onto it, while that value is current: made since the
last command (read-your-writes: every command, and a runner mode's end, marks the
snapshot stale on the simulation's thread before its answer leaves) and at most
``max_age_s`` of wall time ago (what the plant did on its own meanwhile: time
running, a Modbus master's write).  A stale read hops once and publishes afresh;
while that hop is under way, the reads of the same resource that come meanwhile
take the value it replaces if no command ran since and it is at most
``refreshing_s`` old (``recent``): under load the hop waits for the simulation's
thread, and the readers do not all wait with it.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Hashable
from typing import Any, TypeVar

T = TypeVar("T")
MAX_AGE_S = 0.005  # the oldest a snapshot answer may be (wall seconds)
REFRESHING_S = 0.05  # the oldest a value may be while its refresh is under way
MAX_KEYS = 1024  # reads remembered (a device's status, an object's peek...); then cleared


class Snapshot:
    """Values made on the simulation's thread, read from the web server's."""

    def __init__(
        self,
        max_age_s: float = MAX_AGE_S,
        now: Callable[[], float] = time.monotonic,
        refreshing_s: float = REFRESHING_S,
    ) -> None:
        self.max_age_s = max_age_s
        self.refreshing_s = refreshing_s
        self._now = now  # wall seconds (a test's own clock)
        self.version = 0  # written on the simulation's thread only
        self._values: dict[Hashable, tuple[int, float, Any]] = {}

    def changed(self) -> None:
        """The plant changed (a command, a mode's end): every value published is stale."""
        self.version += 1

    def take(self, key: Hashable, fn: Callable[[], T]) -> T:
        """On the simulation's thread: ``fn()`` now, published under ``key``."""
        value = fn()
        if len(self._values) >= MAX_KEYS:
            self._values = {}
        self._values[key] = (self.version, self._now(), value)
        return value

    def get(self, key: Hashable) -> Any | None:
        """The value published under ``key`` if still current, else None."""
        return self._within(key, self.max_age_s)

    def recent(self, key: Hashable) -> Any | None:
        """The value published under ``key`` if no command ran since and it is at most
        ``refreshing_s`` old (a reader's answer while its refresh is under way)."""
        return self._within(key, max(self.refreshing_s, self.max_age_s))

    def _within(self, key: Hashable, age_s: float) -> Any | None:
        found = self._values.get(key)
        if found is None:
            return None
        version, made, value = found
        if version != self.version or self._now() - made > age_s:
            return None
        return value


__all__ = ["MAX_AGE_S", "REFRESHING_S", "Snapshot"]
