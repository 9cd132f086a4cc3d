"""The wall clock the runner paces against, behind a tiny interface.

The runner never calls ``time`` or ``selectors`` itself: it asks a ``WallClock``
for the monotonic time and to wait for ready descriptors.  ``SystemWall`` is
the real one; tests inject a fake so the pacing logic is checked without
sleeping.

Descriptors are registered one at a time (``watch``) and stay registered
between waits, so a connect or a close costs O(1), never a rebuild of the
whole set (issue 10 item 2).  A descriptor is watched for reading, for
writing (while output is queued for it), for both, or forgotten.
"""

from __future__ import annotations

import selectors
import time
from collections.abc import Collection
from typing import Protocol

Ready = tuple[Collection[int], Collection[int]]  # (readable fds, writable fds)


class WallClock(Protocol):
    """Monotonic seconds, and a bounded wait for ready descriptors."""

    def monotonic(self) -> float: ...

    def watch(self, fd: int, read: bool = True, write: bool = False) -> None:
        """Register ``fd`` (or change what it is watched for); neither = ``forget``."""
        ...

    def forget(self, fd: int) -> None:
        """Stop watching ``fd`` (unknown fds are ignored); call it before the fd is closed."""
        ...

    def wait(self, timeout: float | None) -> Ready:
        """Block until a watched fd is ready or ``timeout`` seconds pass."""
        ...


_EVENTS = {
    (True, False): selectors.EVENT_READ,
    (False, True): selectors.EVENT_WRITE,
    (True, True): selectors.EVENT_READ | selectors.EVENT_WRITE,
}


class SystemWall:
    """``time.monotonic`` and one ``selectors.DefaultSelector``, updated incrementally."""

    def __init__(self) -> None:
        self._selector: selectors.BaseSelector = selectors.DefaultSelector()
        self._events: dict[int, int] = {}

    def monotonic(self) -> float:
        return time.monotonic()

    def watch(self, fd: int, read: bool = True, write: bool = False) -> None:
        if not (read or write):
            self.forget(fd)
            return
        events = _EVENTS[(read, write)]
        old = self._events.get(fd)
        if old == events:
            return
        if old is None:
            self._selector.register(fd, events)
        else:
            self._selector.modify(fd, events)
        self._events[fd] = events

    def forget(self, fd: int) -> None:
        if self._events.pop(fd, None) is not None:
            self._selector.unregister(fd)  # an fd closed already: the selector shrugs

    @property
    def watched(self) -> int:
        """How many descriptors are registered."""
        return len(self._events)

    def wait(self, timeout: float | None) -> Ready:
        if not self._events:
            # selectors raise on an empty epoll set with no timeout; sleep instead
            if timeout:
                time.sleep(timeout)
            return (), ()
        readable: list[int] = []
        writable: list[int] = []
        for key, mask in self._selector.select(timeout):
            if mask & selectors.EVENT_READ:
                readable.append(key.fd)
            if mask & selectors.EVENT_WRITE:
                writable.append(key.fd)
        return readable, writable

    def close(self) -> None:
        self._selector.close()
        self._events.clear()
