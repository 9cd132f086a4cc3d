"""The state of the line faults of one TES, and the bounds of their parameters.

:class:`LineFaults` holds what the slave adapter and the RTU line ask about
(``no_answer``, a late answer, corrupted frames, "slave not ready"); the
:class:`fieldtwin.tes.model.Tes` sets them by typed calls (``set_no_answer``,
``set_late_answer``...).  The names users give these faults are in
``fieldtwin.devices.tes.faults``.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable

from fieldtwin.clock import MS
from fieldtwin.errors import ConfigError
from fieldtwin.modbus.model import Link
from fieldtwin.tes import state

LATE_MAX_MS = 60_000  # our bound for a late answer (the TES's own delay stops at 2570 ms, §7.2.7)
COUNT_MAX = 1_000_000  # bound of a fault limited to the next N requests or frames
NOT_READY_WINDOW_MAX_MS = 100  # §6.2.3.2 / §6.4.13: the 32-bit buffers refresh every 100 ms

Param = int | float


def number(name: str, value: object, lo: float, hi: float, unit: str = "") -> Param:
    """A checked numeric fault parameter."""
    if isinstance(value, bool) or not isinstance(value, int | float) or not lo <= value <= hi:
        raise ConfigError(
            f"fault parameter {name}: {value!r} not allowed (allowed {lo:g}..{hi:g}{unit})"
        )
    return value


class LineFaults:
    """The line faults of one TES, on whatever line or endpoint it is reached through."""

    def __init__(self) -> None:
        self.no_answer = False
        self.late_us = 0  # added to the answer delay
        self.corrupt: state.LineFault | None = None  # every frame, until cleared
        self._queued: dict[str, deque[state.LineFault]] = {"rs485": deque(), "rs232": deque()}
        self.not_ready_always = False
        self.not_ready_left = 0  # the next N requests in the 32-bit area
        self.not_ready_window_us = 0  # each 100 ms the TES refreshes its 32-bit buffers this long
        # who closes the TCP connections this TES is reached through (set by the endpoint
        # binder while it serves the TES; each returns how many it closed)
        self.droppers: list[Callable[[], int]] = []

    def active(self) -> dict[str, dict[str, Param]]:
        """The line faults in force, with their parameters."""
        out: dict[str, dict[str, Param]] = {}
        if self.no_answer:
            out["no_answer"] = {}
        if self.late_us:
            out["late_answer"] = {"ms": self.late_us / MS}
        if self.corrupt is not None:
            out[self.corrupt.value] = {}
        for fault in state.LineFault:
            left = sum(q.count(fault) for q in self._queued.values())
            if left:
                out[fault.value] = {"count": left}
        if self.not_ready_always or self.not_ready_left or self.not_ready_window_us:
            params: dict[str, Param] = {}
            if self.not_ready_left and not self.not_ready_always:
                params["count"] = self.not_ready_left
            if self.not_ready_window_us:
                params["window_ms"] = self.not_ready_window_us / MS
            out["not_ready"] = params
        return out

    def set_corrupt(self, fault: state.LineFault, on: bool, count: int | None, link: Link) -> None:
        """Every frame to this TES (count None) or the next ``count`` get ``fault``."""
        for queue in self._queued.values():
            while fault in queue:
                queue.remove(fault)
        if self.corrupt is fault:
            self.corrupt = None
        if on and count is None:
            self.corrupt = fault
        elif on and count is not None:
            self.queue(fault, count, link)

    def queue(self, fault: state.LineFault, count: int, link: Link) -> None:
        """The next ``count`` frames to this TES on ``link`` get ``fault``."""
        self._queued[state.link_key(link)].extend([fault] * count)

    def take(self, link: Link) -> state.LineFault | None:
        """The RTU line asks once per frame it delivers to this TES."""
        queue = self._queued[state.link_key(link)]
        return queue.popleft() if queue else self.corrupt

    def pending(self, link: Link) -> state.LineFault | None:
        """What ``take`` would give, without taking it (for the wire trace)."""
        queue = self._queued[state.link_key(link)]
        return queue[0] if queue else self.corrupt

    def set_not_ready(self, on: bool, count: int | None, window_us: int | None) -> None:
        self.not_ready_always = on and count is None and window_us is None
        self.not_ready_left = (count or 0) if on else 0
        self.not_ready_window_us = (window_us or 0) if on else 0

    def not_ready(self, window: bool) -> bool:
        """One more request in the 32-bit area: is it refused as "not ready"?"""
        if self.not_ready_always:
            return True
        if self.not_ready_left:
            self.not_ready_left -= 1
            return True
        return window
