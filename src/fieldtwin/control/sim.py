"""The bridge from the web server's thread to the simulation's (docs/control.md, "Model").

A request that acts on the plant submits a value: ``Sim.command(name, *args)``
puts a :class:`~fieldtwin.runtime.door.Command` in the runner's inbox, run on
the simulation's thread between two instants by the plant's door (the one
dispatcher, which a recording observes: docs/record.md) with the handler
:func:`serve` gives it - the :class:`~fieldtwin.control.resources.Control`
method of that name.  A request that only reads (``Sim.call(fn)``) submits its
reading function.  Both wait, bounded, for the answer without blocking the web
server's event loop; the plant stays single-threaded and deterministic.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections import deque
from collections.abc import Callable
from typing import Any, TypeVar

from fieldtwin.errors import ConfigError
from fieldtwin.runtime.door import CALL, LINE, Command, Door, Handler
from fieldtwin.runtime.inbox import Answer, Inbox, Ticket

T = TypeVar("T")
DEFAULT_WAIT_S = 10.0  # how long a request waits for its command's result (wall seconds)
MAX_WAIT_S = 3600.0  # the longest a request may ask to wait (a long console advance)

# The control API's commands (docs/record.md): every Control method a route calls that
# may change the plant or the clock.  The pure readers (plant, status, LEDs, lists) are
# readings, not commands; console lines are commands of their own kind (the console's).
COMMANDS = (
    "set_input",
    "set_fault",
    "read_object",
    "write_object",
    "power_cycle",
    "start_exchange",
    "exchange",
    "power_break",
    "remove",
    "insert",
    "pause",
    "resume",
    "step",
    "run_until",
    "set_speed",
)


class CommandTimeout(Exception):
    """The simulation did not finish the command within the request's wait."""


def serve(door: Door, control: object, console: Handler | None = None) -> Callable[[], None]:
    """The door runs the control API's commands with ``control``'s methods of
    :data:`COMMANDS`, and its console lines with ``console`` (the API's console's
    ``handle``); the function returned withdraws them."""

    methods: dict[str, Callable[..., object]] = {name: getattr(control, name) for name in COMMANDS}

    def run(command: Command) -> object:
        method = methods.get(command.name)
        if method is None:
            raise ConfigError(
                f"{command.name[:40]!r} is not a control command (allowed: {', '.join(COMMANDS)})"
            )
        return method(*command.args)

    withdraw = [door.serve(CALL, run)]
    if console is not None:
        withdraw.append(door.serve(LINE, console))

    def withdraw_all() -> None:
        for each in withdraw:
            each()

    return withdraw_all


class _LoopReplies:
    """The answers of one turn of the runner, handed to the web server's loop in one
    call (``Replies``): one wakeup of that loop per turn, not one per command.  The
    other way, the runner is woken once per round of the loop: the commands the loop
    submits while it handles the requests that came together wait for the end of the
    round, and the runner takes them in one turn."""

    def __init__(self, loop: asyncio.AbstractEventLoop, inbox: Inbox) -> None:
        self.loop = loop
        self.inbox = inbox
        self._waking = False  # a wakeup of the runner is due at the end of this round

    def submitted(self, wake: bool) -> None:
        """A command was submitted; ``wake``: the runner must be woken for it."""
        if wake and not self._waking:
            self._waking = True
            self.loop.call_soon(self._wake)

    def _wake(self) -> None:
        self._waking = False
        self.inbox.wake()

    def answer(self, answers: list[Answer]) -> None:
        with contextlib.suppress(RuntimeError):  # the loop has closed: nobody waits
            self.loop.call_soon_threadsafe(_settle, answers)


def _settle(answers: list[Answer]) -> None:
    for future, result, error in answers:
        assert isinstance(future, asyncio.Future)
        if future.done():  # timed out, or its request was cancelled
            continue
        if error is None:
            future.set_result(result)
        else:
            future.set_exception(error)


class _Deadlines:
    """The waits of one loop's requests, bounded: the default wait's in one queue (their
    deadlines come in order) watched by one timer, a longer or shorter wait by a timer
    of its own."""

    def __init__(
        self, loop: asyncio.AbstractEventLoop, inbox: Inbox, queued_s: float = DEFAULT_WAIT_S
    ) -> None:
        self.loop = loop
        self.inbox = inbox
        self.queued_s = queued_s  # the wait of the requests in the queue
        self._queue: deque[tuple[float, Ticket, asyncio.Future[Any]]] = deque()
        self._timer: asyncio.TimerHandle | None = None

    def watch(self, ticket: Ticket, future: asyncio.Future[Any], wait_s: float) -> None:
        if wait_s != self.queued_s:
            timer = self.loop.call_later(wait_s, self._expire, ticket, future, wait_s)
            future.add_done_callback(lambda _: timer.cancel())
            return
        queue = self._queue
        while queue and queue[0][2].done():  # answered: forgotten (the queue stays short)
            queue.popleft()
        queue.append((self.loop.time() + wait_s, ticket, future))
        if self._timer is None:
            self._timer = self.loop.call_at(queue[0][0], self._sweep)

    def _sweep(self) -> None:
        self._timer = None
        queue, now = self._queue, self.loop.time()
        while queue and (queue[0][2].done() or queue[0][0] <= now):
            _, ticket, future = queue.popleft()
            self._expire(ticket, future, self.queued_s)
        if queue:
            self._timer = self.loop.call_at(queue[0][0], self._sweep)

    def _expire(self, ticket: Ticket, future: asyncio.Future[Any], wait_s: float) -> None:
        if future.done():
            return
        # not yet taken, it never runs; taken, its effect stands
        self.inbox.withdraw(ticket)
        future.set_exception(
            CommandTimeout(
                f"the simulation did not finish the command within {wait_s:g} s"
                " (if it had started, its effect stands)"
            )
        )


class Sim:
    """Hands commands to the simulation's thread and waits for their results."""

    def __init__(self, inbox: Inbox, default_wait_s: float = DEFAULT_WAIT_S) -> None:
        self.inbox = inbox
        self.default_wait_s = default_wait_s  # the wait most requests take (one timer)
        # the web server's loop's replies and deadlines (made again for another loop)
        self._replies: _LoopReplies | None = None
        self._deadlines: _Deadlines | None = None

    async def call(self, fn: Callable[[], T], wait_s: float = DEFAULT_WAIT_S) -> T:
        """A reading (or a command's follow-up) run on the simulation's thread."""
        result: T = await self._submit(fn, None, wait_s)
        return result

    async def command(
        self,
        name: str,
        *args: object,
        then: Callable[[Any], Any] | None = None,
        wait_s: float = DEFAULT_WAIT_S,
    ) -> Any:
        """The control command ``name(*args)``, a value through the door; its answer
        (``then(answer)``, read on the simulation's thread in the same turn)."""
        return await self._submit(Command.call(name, *args), then, wait_s)

    async def line(
        self,
        line: str,
        *,
        then: Callable[[Any], Any] | None = None,
        wait_s: float = DEFAULT_WAIT_S,
    ) -> Any:
        """The console line ``line`` (its text after the first newline), a value through
        the door; its output lines (``then(lines)``, read in the same turn)."""
        return await self._submit(Command.line(line), then, wait_s)

    async def _submit(
        self, run: Callable[[], Any] | Command, then: Callable[[Any], Any] | None, wait_s: float
    ) -> Any:
        # one asyncio future, settled with the others of its turn by one call from the
        # simulation's thread; one shared timer for the default wait (a concurrent
        # future, its asyncio twin and a timer per request cost more than the command)
        loop = asyncio.get_running_loop()
        replies, deadlines = self._replies, self._deadlines
        if replies is None or deadlines is None or replies.loop is not loop:
            replies, deadlines = (
                _LoopReplies(loop, self.inbox),
                _Deadlines(loop, self.inbox, self.default_wait_s),
            )
            self._replies, self._deadlines = replies, deadlines
        future: asyncio.Future[Any] = loop.create_future()
        ticket = Ticket(replies, future)
        replies.submitted(self.inbox.submit_ticket(run, ticket, then, wake=False))
        deadlines.watch(ticket, future, wait_s)
        try:
            return await future
        except asyncio.CancelledError:
            self.inbox.withdraw(ticket)  # the request itself was cancelled
            raise


__all__ = ["COMMANDS", "DEFAULT_WAIT_S", "MAX_WAIT_S", "CommandTimeout", "Sim", "serve"]
