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
from collections.abc import Callable
from concurrent.futures import Future
from typing import Any, TypeVar

from fieldtwin.errors import ConfigError
from fieldtwin.runtime.door import CALL, LINE, Command, Door, Handler
from fieldtwin.runtime.inbox import Inbox

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

    def run(command: Command) -> object:
        if command.name not in COMMANDS:
            raise ConfigError(
                f"{command.name[:40]!r} is not a control command (allowed: {', '.join(COMMANDS)})"
            )
        method: Callable[..., object] = getattr(control, command.name)
        return method(*command.args)

    withdraw = [door.serve(CALL, run)]
    if console is not None:
        withdraw.append(door.serve(LINE, console))

    def withdraw_all() -> None:
        for each in withdraw:
            each()

    return withdraw_all


class Sim:
    """Hands commands to the simulation's thread and waits for their results."""

    def __init__(self, inbox: Inbox) -> None:
        self.inbox = inbox

    async def call(self, fn: Callable[[], T], wait_s: float = DEFAULT_WAIT_S) -> T:
        """A reading (or a command's follow-up) run on the simulation's thread."""
        future: Future[T] = self.inbox.submit(fn)
        return await self._wait(future, wait_s)

    async def command(
        self,
        name: str,
        *args: object,
        then: Callable[[Any], Any] | None = None,
        wait_s: float = DEFAULT_WAIT_S,
    ) -> Any:
        """The control command ``name(*args)``, a value through the door; its answer
        (``then(answer)``, read on the simulation's thread in the same turn)."""
        future = self.inbox.submit_command(Command.call(name, *args), then)
        return await self._wait(future, wait_s)

    async def line(
        self,
        line: str,
        *,
        then: Callable[[Any], Any] | None = None,
        wait_s: float = DEFAULT_WAIT_S,
    ) -> Any:
        """The console line ``line`` (its text after the first newline), a value through
        the door; its output lines (``then(lines)``, read in the same turn)."""
        future = self.inbox.submit_command(Command.line(line), then)
        return await self._wait(future, wait_s)

    @staticmethod
    async def _wait(future: Future[T], wait_s: float) -> T:
        # one asyncio future chained to the command's and one timer (asyncio.wait_for
        # adds a waiter future and a callback of its own: every request pays them)
        waiter = asyncio.wrap_future(future)
        expired = False

        def expire() -> None:
            nonlocal expired
            expired = True
            # cancels ``future`` too: not yet started, it never runs; running, its
            # effect stands
            waiter.cancel()

        timer = asyncio.get_running_loop().call_later(wait_s, expire)
        try:
            return await waiter
        except asyncio.CancelledError:
            if not expired:
                raise  # the request itself was cancelled
            raise CommandTimeout(
                f"the simulation did not finish the command within {wait_s:g} s"
                " (if it had started, its effect stands)"
            ) from None
        finally:
            timer.cancel()


__all__ = ["COMMANDS", "DEFAULT_WAIT_S", "MAX_WAIT_S", "CommandTimeout", "Sim", "serve"]
