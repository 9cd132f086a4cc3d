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

import math
import select
import selectors
import time
from collections.abc import Collection
from contextlib import suppress
from typing import Protocol

Ready = tuple[Collection[int], Collection[int]]  # (readable fds, writable fds)

# Issue 15 item 2: epoll (selectors) rounds every timeout up to whole milliseconds, so a
# reply due in 0.3 ms would leave 1 ms late.  A precise wait sleeps in whole ms up to
# PRECISE_SPIN_S before its end, then polls every PRECISE_NAP_S until the end (bounded:
# at most PRECISE_SPIN_S plus the kernel's one-millisecond rounding).
PRECISE_SPIN_S = 0.0015
PRECISE_NAP_S = 0.0001  # a nap between two polls: never a busy loop holding the GIL
# Issue 15 item 2: while precise waits are wanted, the runner runs an instant this much
# wall time before it is due, so that a reply written then reaches the master on a pty
# at its instant: what the master's process and the pty's transfer take on the way
# (about 0.2-0.5 ms at every baud rate on the machines measured; docs/modbus.md).
PRECISE_LEAD_S = 0.00025
# Issue 13: at ``--speed max`` the runner polls the descriptors between two instants
# only once this much wall time has passed since the last poll (Runner, "fast"): a
# select per instant was a quarter of the default plant's time.
FAST_POLL_S = 0.0001


class WallClock(Protocol):
    """Monotonic seconds, a bounded wait for ready descriptors, and the wall's abilities
    the runner's pacing uses (typed: a wall without one says 0 or ignores the wish)."""

    @property
    def fast_poll_s(self) -> float:
        """At ``--speed max``, the least wall time between two polls of the descriptors
        while events run (0: a poll between every two instants)."""
        ...

    @property
    def lead_s(self) -> float:
        """How early (wall seconds) the runner may run a due instant (0: on time)."""
        ...

    def want_precision(self, on: bool) -> None:
        """A user needs waits that end on time to a fraction of a millisecond (``on``),
        or no longer does (counted); a wall that cannot ignores it."""
        ...

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


_EPOLL_MASK = {  # selectors' events -> epoll's
    selectors.EVENT_READ: select.EPOLLIN if hasattr(select, "epoll") else 0,
    selectors.EVENT_WRITE: select.EPOLLOUT if hasattr(select, "epoll") else 0,
}


def _epoll_mask(events: int) -> int:
    return sum(mask for event, mask in _EPOLL_MASK.items() if events & event)


# selectors' reading of an epoll event: anything but "writable" (an error, a hang-up)
# makes a descriptor readable, anything but "readable" makes it writable
_NOT_OUT = ~_EPOLL_MASK[selectors.EVENT_WRITE]
_NOT_IN = ~_EPOLL_MASK[selectors.EVENT_READ]


class SystemWall:
    """``time.monotonic`` and one epoll set (Linux) or ``selectors.DefaultSelector``
    (elsewhere, or ``epoll=False``), updated incrementally.

    The epoll set is used directly: selectors' ``select`` builds a key object per ready
    descriptor and looks it up, a few microseconds of Python per wait that the runner
    pays once a request at one connection (docs/decisions.md, "The runner's cycle").
    Both say the same: a descriptor in error or hung up is ready for what it is watched
    for, as selectors says it."""

    fast_poll_s = FAST_POLL_S  # the runner's least wall time between polls while busy

    def __init__(self, epoll: bool = True) -> None:
        self._epoll = select.epoll() if epoll and hasattr(select, "epoll") else None
        self._selector: selectors.BaseSelector | None = (
            None if self._epoll is not None else selectors.DefaultSelector()
        )
        self._events: dict[int, int] = {}
        self._precise = 0  # how many users want precise waits (want_precision)

    # the C function itself, no Python frame around it (called twice a runner cycle)
    monotonic = staticmethod(time.monotonic)

    def watch(self, fd: int, read: bool = True, write: bool = False) -> None:
        if not (read or write):
            self.forget(fd)
            return
        events = _EVENTS[(read, write)]
        old = self._events.get(fd)
        if old == events:
            return
        if self._epoll is not None:
            mask = _epoll_mask(events)
            if old is None:
                self._epoll.register(fd, mask)
            else:
                self._epoll.modify(fd, mask)
        elif old is None:
            assert self._selector is not None
            self._selector.register(fd, events)
        else:
            assert self._selector is not None
            self._selector.modify(fd, events)
        self._events[fd] = events

    def forget(self, fd: int) -> None:
        if self._events.pop(fd, None) is not None:
            if self._epoll is not None:
                with suppress(OSError):  # an fd closed already (as selectors shrugs)
                    self._epoll.unregister(fd)
            else:
                assert self._selector is not None
                self._selector.unregister(fd)  # an fd closed already: the selector shrugs

    @property
    def watched(self) -> int:
        """How many descriptors are registered."""
        return len(self._events)

    def want_precision(self, on: bool) -> None:
        """A user (a wire-timed RTU line) needs waits that end on time to a fraction of a
        millisecond (``on``), or no longer does; precise waits cost a short poll loop."""
        self._precise = max(0, self._precise + (1 if on else -1))

    @property
    def precise(self) -> bool:
        return self._precise > 0

    @property
    def lead_s(self) -> float:
        """How early (wall seconds) the runner may run a due instant: PRECISE_LEAD_S
        while precise waits are wanted, else 0."""
        return PRECISE_LEAD_S if self._precise > 0 else 0.0

    def wait(self, timeout: float | None) -> Ready:
        if not self._events:
            # selectors raise on an empty epoll set with no timeout; sleep instead
            if timeout:
                time.sleep(timeout)  # clock_nanosleep: not rounded to whole ms
            return (), ()
        if self._precise and timeout is not None and timeout > 0:
            return self._precise_wait(timeout)
        return self._select(timeout)

    def _precise_wait(self, timeout: float) -> Ready:
        end = time.monotonic() + timeout
        coarse_ms = math.floor((timeout - PRECISE_SPIN_S) * 1000)
        if coarse_ms > 0:
            ready = self._select(coarse_ms / 1000)
            if ready[0] or ready[1]:
                return ready
        while True:  # the last < 2.5 ms: poll, napping PRECISE_NAP_S (other threads run)
            ready = self._select(0)
            left = end - time.monotonic()
            if ready[0] or ready[1] or left <= 0:
                return ready
            time.sleep(min(left, PRECISE_NAP_S))  # clock_nanosleep: not rounded to ms

    def _select(self, timeout: float | None) -> Ready:
        readable: list[int] = []
        writable: list[int] = []
        epoll = self._epoll
        if epoll is not None:
            # as selectors.EpollSelector: no timeout is -1, a timeout rounded up to a ms
            if timeout is None:
                wait = -1.0
            elif timeout <= 0:
                wait = 0.0
            else:
                wait = math.ceil(timeout * 1e3) * 1e-3
            events = self._events
            for fd, got in epoll.poll(wait, max(len(events), 1)):
                wanted = events.get(fd, 0)
                if got & _NOT_OUT and wanted & selectors.EVENT_READ:
                    readable.append(fd)
                if got & _NOT_IN and wanted & selectors.EVENT_WRITE:
                    writable.append(fd)
            return readable, writable
        assert self._selector is not None
        for key, mask in self._selector.select(timeout):
            if mask & selectors.EVENT_READ:
                readable.append(key.fd)
            if mask & selectors.EVENT_WRITE:
                writable.append(key.fd)
        return readable, writable

    def close(self) -> None:
        if self._epoll is not None:
            self._epoll.close()
        else:
            assert self._selector is not None
            self._selector.close()
        self._events.clear()
