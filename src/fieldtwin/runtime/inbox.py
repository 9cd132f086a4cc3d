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

A requester on an event loop (the control API) submits with a :class:`Ticket`
instead of a future: the runner hands every answer of one turn to the ticket's
:class:`Replies` at once, at the end of the turn (one wakeup of the loop per turn,
not one per command), and a ticket withdrawn before its turn is skipped.
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
from typing import Any, NamedTuple, Protocol, TypeVar

from fieldtwin.errors import FieldtwinError
from fieldtwin.runtime.door import Command, Door

T = TypeVar("T")
MAX_PENDING = 256  # commands waiting for the runner before submit refuses
WAKEUPS_READ = 4096  # bytes of wakeups taken by one read (one byte per wakeup)


class InboxFull(FieldtwinError):
    """More than ``max_pending`` commands wait for the simulation."""


class InboxClosed(FieldtwinError):
    """The simulation has ended: nobody will run the command."""


Answer = tuple[object, Any, BaseException | None]  # a ticket's key, its result, its error


class Replies(Protocol):
    """Takes the answers of a turn's tickets, all at once, on the simulation's thread
    (an event loop's: one ``call_soon_threadsafe`` for them all)."""

    def answer(self, answers: list[Answer]) -> None: ...


@dataclass(slots=True, eq=False)
class Ticket:
    """A command's place in the inbox for a requester that takes its answers by turns:
    ``key`` is the requester's own (its future), given back with the answer."""

    replies: Replies
    key: object
    taken: bool = False  # its turn came (set under the inbox's lock)
    withdrawn: bool = False  # its requester gave up before its turn (idem)


class _Command(NamedTuple):  # a tuple: made at each request, the cheapest to make
    run: Callable[[], Any] | Command
    future: Future[Any] | Ticket
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
        # wakeups sent (counted under the lock, after the byte) and those the runner
        # has read past: it reads the descriptor only when they differ, not every cycle
        self._sent = 0
        self._drained = 0
        self.closed = False
        self.executed = 0  # commands run so far
        self._turn: dict[Replies, list[Answer]] | None = None  # the answers of the turn

    def fileno(self) -> int:
        """Readable while commands are pending (the runner watches it)."""
        return self._reader.fileno()

    def submit(self, run: Callable[[], T]) -> Future[T]:
        """From any thread: run ``run()`` on the simulation's thread; its future."""
        future: Future[T] = Future()
        self._submit(_Command(run, future))
        return future

    def submit_command(
        self, command: Command, then: Callable[[Any], Any] | None = None
    ) -> Future[Any]:
        """From any thread: ``command`` run by the door on the simulation's thread; its
        future gives its answer (``then(answer)`` when given, read in the same turn)."""
        if self.door is None:
            raise ValueError("this inbox has no door to run commands")
        future: Future[Any] = Future()
        self._submit(_Command(command, future, then))
        return future

    def submit_ticket(
        self,
        run: Callable[[], Any] | Command,
        ticket: Ticket,
        then: Callable[[Any], Any] | None = None,
        *,
        wake: bool = True,
    ) -> bool:
        """From any thread: ``run`` (a reading function, or a command for the door) on
        the simulation's thread; its answer goes to ``ticket.replies`` with the turn's
        others (``then(answer)`` when given, read in the same turn).  With ``wake`` False
        the runner is not woken here: True is returned when it must be, by ``wake()``
        (an event loop wakes it once for all it submitted in one round)."""
        if isinstance(run, Command) and self.door is None:
            raise ValueError("this inbox has no door to run commands")
        return self._submit(_Command(run, ticket, then), wake)

    def wake(self) -> None:
        """From any thread: the runner looks at the inbox (a wakeup deferred by
        ``submit_ticket(..., wake=False)``)."""
        with contextlib.suppress(BlockingIOError, OSError):  # full of wakeups, or closed
            self._writer.send(b"\0")
        self._count_wakeup()

    def withdraw(self, ticket: Ticket) -> bool:
        """From any thread: ``ticket``'s command will not run, if its turn has not come
        (True); False when it has (it runs, or ran: its effect stands)."""
        with self._lock:
            if ticket.taken:
                return False
            ticket.withdrawn = True
            return True

    def _submit(self, item: _Command, wake_now: bool = True) -> bool:
        with self._lock:
            if self.closed:
                raise InboxClosed("the simulation has stopped")
            if len(self._queue) >= self.max_pending:
                raise InboxFull(f"{self.max_pending} commands already wait for the simulation")
            # a command already waiting has sent its wakeup, and the runner takes the whole
            # queue after it drains the wakeups: this one is taken in the same turn
            wake = not self._queue
            self._queue.append(item)
        if wake and wake_now:
            with contextlib.suppress(BlockingIOError):  # full of wakeups already: it will look
                self._writer.send(b"\0")
            self._count_wakeup()
        return wake

    def _count_wakeup(self) -> None:
        """After a wakeup byte is sent (or the descriptor was full of them)."""
        with self._lock:
            self._sent += 1

    def __len__(self) -> int:
        return len(self._queue)

    def run_pending(self) -> int:
        """On the simulation's thread: run what was submitted before now; how many ran.
        The tickets' answers leave together at the end, by their ``Replies``."""
        sent = self._sent
        if sent != self._drained:  # a wakeup was sent since the last read: read them all
            self._drained = sent
            self._drain_wakeups()
        elif not self._queue:
            return 0  # nothing sent, nothing waiting: no system call, no lock
        with self._lock:
            commands = list(self._queue)
            self._queue.clear()
            for command in commands:
                if isinstance(command.future, Ticket):
                    command.future.taken = True
        answers: dict[Replies, list[Answer]] = {}
        self._turn = answers
        done = 0
        try:
            for command in commands:
                done += 1
                future = command.future
                if isinstance(future, Ticket):
                    if future.withdrawn:
                        continue
                    result, error = self._run(command)
                    answers.setdefault(future.replies, []).append((future.key, result, error))
                else:
                    if not future.set_running_or_notify_cancel():
                        continue  # its requester gave up before its turn
                    result, error = self._run(command)
                    if error is None:
                        future.set_result(result)
                    else:
                        future.set_exception(error)
                self.executed += 1
                if error is not None and not isinstance(error, Exception):
                    raise error  # Ctrl-C, SystemExit: the requester is told, then the run stops
        finally:
            for command in commands[done:]:  # not run: the run stops
                future = command.future
                stopped = InboxClosed("the simulation has stopped")
                if isinstance(future, Ticket):
                    answers.setdefault(future.replies, []).append((future.key, None, stopped))
                elif future.set_running_or_notify_cancel():
                    future.set_exception(stopped)
            self._turn = None
            for replies, given in answers.items():
                replies.answer(given)
        return len(commands)

    def flush(self) -> None:
        """On the simulation's thread, inside a turn: the answers of the turn so far leave
        now (a command that runs the clock would hold them until it ends)."""
        turn = self._turn
        if not turn:
            return
        given = list(turn.items())
        turn.clear()
        for replies, answers in given:
            replies.answer(answers)

    def _run(self, command: _Command) -> tuple[Any, BaseException | None]:
        """A command's answer or what it raised (the requester gets it; an Exception
        leaves the plant running)."""
        try:
            run = command.run
            if isinstance(run, Command):
                assert self.door is not None
                result = self.door.dispatch(run)
                if command.then is not None:
                    result = command.then(result)
            else:
                result = run()
        except BaseException as exc:
            return None, exc
        return result, None

    def wait(self, timeout: float) -> bool:
        """Block up to ``timeout`` seconds for a command; True if one is pending."""
        if self._queue:
            return True
        ready, _, _ = select.select([self._reader], [], [], timeout)
        return bool(ready) or bool(self._queue)

    def _drain_wakeups(self) -> None:
        # one read takes every wakeup (one is sent per empty queue, so a few at most),
        # more if a read comes back full (the runner reads again only once the count of
        # wakeups sent moves); a wakeup sent after it counts: one more turn, harmless
        with contextlib.suppress(BlockingIOError, OSError):
            while len(self._reader.recv(WAKEUPS_READ)) == WAKEUPS_READ:
                pass  # more than one read's worth (bounded: the queue is): read on

    def close(self) -> None:
        """No more commands; those still waiting fail with InboxClosed."""
        with self._lock:
            if self.closed:
                return
            self.closed = True
            left = list(self._queue)
            self._queue.clear()
        answers: dict[Replies, list[Answer]] = {}
        for command in left:
            future = command.future
            if isinstance(future, Ticket):
                if not future.withdrawn:
                    closed = InboxClosed("the simulation has stopped")
                    answers.setdefault(future.replies, []).append((future.key, None, closed))
            elif future.set_running_or_notify_cancel():
                future.set_exception(InboxClosed("the simulation has stopped"))
        for replies, given in answers.items():
            replies.answer(given)
        self._reader.close()
        self._writer.close()


__all__ = ["MAX_PENDING", "Answer", "Inbox", "InboxClosed", "InboxFull", "Replies", "Ticket"]
