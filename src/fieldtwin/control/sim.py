"""The bridge from the web server's thread to the simulation's (docs/control.md, "Model").

``Sim.call(fn)`` submits ``fn`` to the runner's inbox and waits, bounded, for
its result without blocking the web server's event loop.  Everything that
touches the plant is such a function: it runs on the simulation's thread
between two instants, so the plant stays single-threaded and deterministic.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import TypeVar

from fieldtwin.runtime.inbox import Inbox

T = TypeVar("T")
DEFAULT_WAIT_S = 10.0  # how long a request waits for its command's result (wall seconds)
MAX_WAIT_S = 3600.0  # the longest a request may ask to wait (a long console advance)


class CommandTimeout(Exception):
    """The simulation did not finish the command within the request's wait."""


class Sim:
    """Hands commands to the simulation's thread and waits for their results."""

    def __init__(self, inbox: Inbox) -> None:
        self.inbox = inbox

    async def call(self, fn: Callable[[], T], wait_s: float = DEFAULT_WAIT_S) -> T:
        future = self.inbox.submit(fn)
        try:
            return await asyncio.wait_for(asyncio.wrap_future(future), wait_s)
        except TimeoutError:
            future.cancel()  # not yet started: it never runs; running: its effect stands
            raise CommandTimeout(
                f"the simulation did not finish the command within {wait_s:g} s"
                " (if it had started, its effect stands)"
            ) from None


__all__ = ["DEFAULT_WAIT_S", "MAX_WAIT_S", "CommandTimeout", "Sim"]
