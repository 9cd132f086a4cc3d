"""What every router shares: the hop onto the simulation's thread, the snapshot
reads, and the wait for a runner mode's end."""

from __future__ import annotations

import asyncio
from collections.abc import Callable, Hashable
from concurrent.futures import Future
from typing import Any, TypeVar

from fieldtwin.control.resources import Control, Json
from fieldtwin.control.sim import DEFAULT_WAIT_S, Sim

T = TypeVar("T")
MODE_POLL_S = 0.25  # a request waiting for a mode's end looks this often for a stopped run
REPLY: dict[str, Any] = {"response_model_exclude_unset": True}  # optional keys left out


class Hop:
    """The routes' way to the plant: ``run`` a command on the simulation's thread
    (the snapshot is stale after it: read-your-writes), or ``read`` what changes
    nothing from the snapshot the simulation published."""

    def __init__(self, control: Control, sim: Sim) -> None:
        self.control = control
        self.sim = sim
        self.snapshot = control.snapshot
        # the hop in flight for each read, with the snapshot's version when it left
        # (on the web server's loop only): the reads that come meanwhile share it
        self._pending: dict[Hashable, tuple[int, asyncio.Future[Any]]] = {}

    async def run(self, fn: Callable[[], T], wait_s: float = DEFAULT_WAIT_S) -> T:
        snapshot = self.snapshot

        def command() -> T:
            try:
                return fn()
            finally:
                snapshot.changed()  # before the answer: a later read sees the effect

        return await self.sim.call(command, wait_s)

    async def do(
        self,
        name: str,
        *args: object,
        then: Callable[[Any], Any] | None = None,
        wait_s: float = DEFAULT_WAIT_S,
    ) -> Any:
        """The control command ``name(*args)``: a value through the plant's door (which
        a recording observes); the snapshot goes stale at the door, before the answer."""
        return await self.sim.command(name, *args, then=then, wait_s=wait_s)

    async def read(self, key: Hashable, fn: Callable[[], T]) -> T:
        snapshot = self.snapshot
        found = snapshot.get(key)
        if found is not None:
            value: T = found
            return value
        version = snapshot.version
        pending = self._pending.get(key)
        if pending is not None and pending[0] == version:
            # a refresh is under way and no command ran since: the value it replaces,
            # if recent enough (Snapshot.recent), else the refresh's own (made after
            # this request came, so it is this request's answer too)
            recent = snapshot.recent(key)
            if recent is not None:
                kept: T = recent
                return kept
            shared: T = await asyncio.shield(pending[1])
            return shared
        hop = asyncio.ensure_future(self.sim.call(lambda: snapshot.take(key, fn)))
        self._pending[key] = (version, hop)

        def done(_: object) -> None:
            if self._pending.get(key, (0, None))[1] is hop:
                del self._pending[key]

        hop.add_done_callback(done)
        mine: T = await asyncio.shield(hop)
        return mine


async def mode(hop: Hop, start: tuple[str, float | None], wait: bool, wait_s: float) -> Json:
    """Start a runner mode (the command ``start``: step, run-until, power-break); its
    state at once, or with ``wait`` at its end (at most ``wait_s``; the run stopping
    ends the wait too)."""
    c = hop.control
    begun: tuple[Json, Future[Json] | None] = await hop.do(
        *start, then=lambda state: (state, c.mode_ended)
    )
    state, ended = begun
    if not wait or ended is None:
        return state
    result = await mode_end(c, ended, wait_s)
    if result is not None:
        return result
    return await hop.run(c.clock_state)  # still running: the mode as it stands


async def mode_end(c: Control, ended: Future[Json], wait_s: float) -> Json | None:
    """The end of a mode (its clock state), awaited at most ``wait_s``; None if it
    has not ended by then or the run stops."""
    done = asyncio.wrap_future(ended)
    loop = asyncio.get_running_loop()
    deadline = loop.time() + wait_s
    try:
        while not done.done() and c.runner.running and loop.time() < deadline:
            await asyncio.wait({done}, timeout=min(MODE_POLL_S, deadline - loop.time()))
        ended_now = done.done() and not done.cancelled()
    finally:
        if not done.done():
            done.cancel()  # the mode's own future runs on (it cannot be cancelled)
    return done.result() if ended_now else None


__all__ = ["MODE_POLL_S", "REPLY", "Hop", "mode", "mode_end"]
