"""Commands entering the simulation at an instant the runner chooses (DESIGN rule 13).

Another thread (the control API's web server) ``submit``s a command - a
:class:`~fieldtwin.runtime.door.Command` value, run by the plant's door (the one
dispatcher, which a recording observes), or a function that only reads - and
gets a ``concurrent.futures.Future``; the runner, which watches the inbox's wakeup
descriptor beside its transports, runs the pending functions on the simulation's
thread between two instants (``run_pending``), in the order they were submitted,
and sets each future's result or exception.  A future cancelled before its turn
is skipped.  The inbox is bounded (``max_pending``): past it, ``submit`` raises
``InboxFull`` at once, so a flood of requests never grows memory.
"""

from __future__ import annotations

import contextlib
import select
import socket
import threading
from collections import deque
from collections.abc import Callable
from concurrent.futures import Future
from dataclasses import dataclass
from typing import Any, TypeVar

from fieldtwin.errors import FieldtwinError
from fieldtwin.runtime.door import Command, Door

T = TypeVar("T")
MAX_PENDING = 256  # commands waiting for the runner before submit refuses


class InboxFull(FieldtwinError):
    """More than ``max_pending`` commands wait for the simulation."""


class InboxClosed(FieldtwinError):
    """The simulation has ended: nobody will run the command."""


@dataclass(frozen=True, slots=True)
class _Command:
    run: Callable[[], Any] | Command
    future: Future[Any]
    then: Callable[[Any], Any] | None = None  # the answer's reading, in the same turn


class Inbox:
    """A bounded, thread-safe queue of commands with a wakeup descriptor: a socket pair,
    not a pipe, so that select() takes it everywhere (on Windows it takes sockets only)."""

    def __init__(self, max_pending: int = MAX_PENDING, door: Door | None = None) -> None:
        if max_pending < 1:
            raise ValueError("an inbox holds at least one command")
        self.max_pending = max_pending
        self.door = door  # what runs the Command values (None: functions only)
        self._reader, self._writer = socket.socketpair()
        self._reader.setblocking(False)
        self._writer.setblocking(False)
        self._queue: deque[_Command] = deque()
        self._lock = threading.Lock()
        self.closed = False
        self.executed = 0  # commands run so far

    def fileno(self) -> int:
        """Readable while commands are pending (the runner watches it)."""
        return self._reader.fileno()

    def submit(self, run: Callable[[], T]) -> Future[T]:
        """From any thread: run ``run()`` on the simulation's thread; its future."""
        return self._submit(_Command(run, Future()))

    def submit_command(
        self, command: Command, then: Callable[[Any], Any] | None = None
    ) -> Future[Any]:
        """From any thread: ``command`` run by the door on the simulation's thread; its
        future gives its answer (``then(answer)`` when given, read in the same turn)."""
        if self.door is None:
            raise ValueError("this inbox has no door to run commands")
        return self._submit(_Command(command, Future(), then))

    def _submit(self, item: _Command) -> Future[Any]:
        future = item.future
        with self._lock:
            if self.closed:
                raise InboxClosed("the simulation has stopped")
            if len(self._queue) >= self.max_pending:
                raise InboxFull(f"{self.max_pending} commands already wait for the simulation")
            # a command already waiting has sent its wakeup, and the runner takes the whole
            # queue after it drains the wakeups: this one is taken in the same turn
            wake = not self._queue
            self._queue.append(item)
        if wake:
            with contextlib.suppress(BlockingIOError):  # full of wakeups already: it will look
                self._writer.send(b"\0")
        return future

    def __len__(self) -> int:
        return len(self._queue)

    def run_pending(self) -> int:
        """On the simulation's thread: run what was submitted before now; how many ran."""
        self._drain_wakeups()
        with self._lock:
            commands = list(self._queue)
            self._queue.clear()
        for command in commands:
            if not command.future.set_running_or_notify_cancel():
                continue  # its requester gave up before its turn
            try:
                run = command.run
                if isinstance(run, Command):
                    assert self.door is not None
                    result = self.door.dispatch(run)
                    if command.then is not None:
                        result = command.then(result)
                else:
                    result = run()
            except Exception as exc:  # the requester gets it; the plant keeps running
                command.future.set_exception(exc)
            except BaseException as exc:  # Ctrl-C, SystemExit: tell the requester, then stop
                command.future.set_exception(exc)
                raise
            else:
                command.future.set_result(result)
            self.executed += 1
        return len(commands)

    def wait(self, timeout: float) -> bool:
        """Block up to ``timeout`` seconds for a command; True if one is pending."""
        if self._queue:
            return True
        ready, _, _ = select.select([self._reader], [], [], timeout)
        return bool(ready) or bool(self._queue)

    def _drain_wakeups(self) -> None:
        try:
            while self._reader.recv(4096):
                pass
        except (BlockingIOError, OSError):
            pass

    def close(self) -> None:
        """No more commands; those still waiting fail with InboxClosed."""
        with self._lock:
            if self.closed:
                return
            self.closed = True
            left = list(self._queue)
            self._queue.clear()
        for command in left:
            if command.future.set_running_or_notify_cancel():
                command.future.set_exception(InboxClosed("the simulation has stopped"))
        self._reader.close()
        self._writer.close()


__all__ = ["MAX_PENDING", "Inbox", "InboxClosed", "InboxFull"]
