"""The wall clock the runner paces against, behind a tiny interface.

The runner never calls ``time`` or ``selectors`` itself: it asks a ``WallClock``
for the monotonic time and to wait for readable descriptors.  ``SystemWall`` is
the real one; tests inject a fake so the pacing logic is checked without
sleeping.
"""

from __future__ import annotations

import selectors
import time
from collections.abc import Collection, Sequence
from typing import Protocol


class WallClock(Protocol):
    """Monotonic seconds, and a bounded wait for readable descriptors."""

    def monotonic(self) -> float: ...

    def wait(self, fds: Sequence[int], timeout: float | None) -> Collection[int]:
        """Block until one of ``fds`` is readable or ``timeout`` seconds pass; the ready fds.

        The runner passes a new ``fds`` object whenever its set of descriptors
        changes, so an implementation may cache its registrations by identity.
        """
        ...


class SystemWall:
    """``time.monotonic`` and a cached ``selectors.DefaultSelector``."""

    def __init__(self) -> None:
        self._selector: selectors.BaseSelector | None = None
        self._fds: Sequence[int] | None = None

    def monotonic(self) -> float:
        return time.monotonic()

    def wait(self, fds: Sequence[int], timeout: float | None) -> Collection[int]:
        if fds is not self._fds or self._selector is None:
            self._register(fds)
        assert self._selector is not None
        return [key.fd for key, _ in self._selector.select(timeout)]

    def _register(self, fds: Sequence[int]) -> None:
        # A fresh selector each time the set changes: a closed fd's number may be reused.
        self.close()
        selector = selectors.DefaultSelector()
        for fd in fds:
            selector.register(fd, selectors.EVENT_READ)
        self._selector = selector
        self._fds = fds

    def close(self) -> None:
        if self._selector is not None:
            self._selector.close()
        self._selector = None
        self._fds = None
